// PIBT in the rotation action model, over short operations (see pibt.hpp). After EPIBT (Nagorny
// et al., "EPIBT", LoRR 2024, arXiv 2511.09193) and PIBT (Okumura et al., AIJ 2022).
#include <algorithm>
#include <array>
#include <chrono>
#include <climits>
#include <numeric>
#include <system_error>
#include <thread>

#include "gdrhcr/pibt.hpp"

namespace gdrhcr {

namespace {
constexpr int kFree = -1;
constexpr int kFixed = -2;  // a cell held by an agent outside the call (or blocked)
constexpr int kBlocked = -2;  // blocker(): a fixed cell, or more than one agent in the way

using Operation = std::array<Action, PibtStep::kOpSteps>;
constexpr Action kAll[4] = {Action::kForward, Action::kClockwise, Action::kCounterClockwise, Action::kWait};
constexpr int kCodes = 1 << (2 * PibtStep::kOpSteps);  // 4^kOpSteps sequences of actions
constexpr int kWww = kCodes - 1;  // the code of waiting throughout (code: action k is kAll[code / 4^k % 4])

bool is_turn(Action a) { return a == Action::kClockwise || a == Action::kCounterClockwise; }

Operation decode(int code) {
  Operation op{};
  for (int k = 0; k < PibtStep::kOpSteps; ++k, code /= 4) op[k] = kAll[code % 4];
  return op;
}

// Every sequence of kOpSteps actions except: a turn right after the opposite one (they cancel),
// two counter-clockwise turns in a row (two clockwise ones reach the same state), and a turn as
// the last action (the next step plans again; the same operation ending in a wait holds the same
// cells). The operation carried on from one step to the next (its last actions, then a wait) is
// kept by these rules.
bool kept_operation(const Operation& op) {
  if (is_turn(op[PibtStep::kOpSteps - 1])) return false;
  for (int k = 1; k < PibtStep::kOpSteps; ++k)
    if (is_turn(op[k - 1]) && is_turn(op[k]) && (op[k] != op[k - 1] || op[k] == Action::kCounterClockwise))
      return false;
  return true;
}

const std::vector<int>& operation_codes() {
  static const std::vector<int> codes = [] {
    std::vector<int> c;
    for (int code = 0; code < kCodes; ++code)
      if (kept_operation(decode(code))) c.push_back(code);
    return c;
  }();
  return codes;
}

// The operation left of `code` after its first action: the rest, then a wait.
int carried_code(int code) { return code / 4 + 3 * (kCodes / 4); }

// Runs `first` here and `second` on another thread when `parallel` and one can be had, else
// after `first`; returns when both are done.
template <class First, class Second>
void both(bool parallel, First&& first, Second&& second) {
  std::thread other;
  if (parallel) {
    try {
      other = std::thread(second);
    } catch (const std::system_error&) {  // no thread to be had: both here
    }
  }
  first();
  if (other.joinable()) other.join();
  else second();
}
}  // namespace

void PibtStep::reserve(int ai, double& score) {
  const OpPath& p = op_[ai].held.path;
  for (int k = 1; k <= kOpSteps; ++k) res(k, p.cell[k]) = ai;
  score += op_power_[ai] * (op_wait_cost_[ai] - op_[ai].held.cost);
}

void PibtStep::release(int ai, double& score) {
  const OpPath& p = op_[ai].held.path;
  for (int k = 1; k <= kOpSteps; ++k)
    if (res(k, p.cell[k]) == ai) res(k, p.cell[k]) = kFree;
  score -= op_power_[ai] * (op_wait_cost_[ai] - op_[ai].held.cost);
}

// The one agent whose reserved cells (or a move crossing one of p's) operation p of ai meets:
// kFree for none, kBlocked for a fixed cell or more than one agent.
int PibtStep::blocker(int ai, const OpPath& p) const {
  int who = kFree;
  auto meet = [&](int v) {
    if (v == kFree || v == ai) return true;
    if (v == kFixed) return false;
    if (who == kFree) who = v;
    return who == v;
  };
  for (int k = 1; k <= kOpSteps; ++k) {
    const Cell c = p.cell[k], before = p.cell[k - 1];
    if (!meet(res(k, c))) return kBlocked;
    if (before == c) continue;
    const int u = k == 1 ? occupied_now_[c] : res(k - 1, c);  // who is at c before ai gets there
    if (u >= 0 && u != ai && res(k, before) == u && !meet(u)) return kBlocked;
  }
  return who;
}

// ai's operations, best first: one starting with the preferred cell's action (a guidance path),
// then the least cost, then the fewest leading waits (an agent asked to give way that puts it
// off is asked again at the next step), then the earliest progress, then at random.
void PibtStep::order_operations(const WorldView& world, int ai, std::mt19937_64& rng) {
  const Pose start = world.pose(ai);
  const DistRow& row = *rows_[ai];
  const Cell pref = preferred_ ? (*preferred_)[ai] : kNoCell;
  const Heading pref_h = pref == kNoCell ? kNoHeading : heading_of_move(grid_, start.cell, pref);
  OpChoice* cand = &op_cand_[size_t(ai) * kMaxOps];
  std::array<std::pair<long long, int>, kMaxOps> keyed;
  OpChoice found[kMaxOps];
  // The pose after each prefix of actions, and its distance (with turns), once per prefix: level l
  // holds the prefixes of l actions, prefix p's action k being kAll[p / 4^k % 4] as in the codes.
  // Operations share their prefixes, so this reads the row about half as often as each operation
  // on its own (10,000 agents list theirs at every call).
  Pose pose[kOpSteps][kMaxOps];
  int dist[kOpSteps][kMaxOps];
  auto step = [&](const Pose& from, Action a, Pose& to, int& d) {
    to = from.cell == kNoCell ? from : apply_action(grid_, from, a);
    d = to.cell == kNoCell ? kUnreachable : std::min(row.at(to.cell, to.heading), 1 << 20);
  };
  for (int l = 1, width = 4; l < kOpSteps; ++l, width *= 4)
    for (int p = 0; p < width; ++p)
      step(l == 1 ? start : pose[l - 2][p % (width / 4)], kAll[p / (width / 4)], pose[l - 1][p], dist[l - 1][p]);
  constexpr int kLast = kMaxOps / 4;  // 4^(kOpSteps - 1): prefixes of all but the last action
  int m = 0;
  for (int code : operation_codes()) {
    Pose& end = pose[kOpSteps - 1][code];
    step(kOpSteps == 1 ? start : pose[kOpSteps - 2][code % kLast], kAll[code / kLast], end, dist[kOpSteps - 1][code]);
    if (end.cell == kNoCell) continue;
    OpChoice& c = found[m];
    c.path.cell[0] = start.cell, c.path.heading[0] = start.heading;
    int reached = -1, sum = 0;
    for (int k = 1, width = 4; k <= kOpSteps; ++k, width *= 4) {
      const int p = k == kOpSteps ? code : code % width;
      const Pose& q = pose[k - 1][p];
      c.path.cell[k] = q.cell, c.path.heading[k] = q.heading;
      if (q.cell == goal_of_[ai] && reached < 0) reached = k;
      sum += dist[k - 1][p];
    }
    c.cost = reached >= 0 ? reached : kOpSteps + 1 + dist[kOpSteps - 1][code];
    c.code = static_cast<int16_t>(code);
    const Operation op = decode(code);
    bool preferred = false;
    if (pref == start.cell) preferred = op[0] == Action::kWait;
    else if (pref_h != kNoHeading)
      preferred = op[0] == Action::kForward ? pref_h == start.heading
                  : op[0] != Action::kWait && turn_steps(c.path.heading[1], pref_h) < turn_steps(start.heading, pref_h);
    int waits = 0;
    while (waits < kOpSteps && op[waits] == Action::kWait) ++waits;
    keyed[m] = {((preferred ? 0LL : 1LL) << 50) + (static_cast<long long>(c.cost) << 26) +
                    (static_cast<long long>(waits) << 22) + std::min(sum, (1 << 22) - 1),
                m};
    ++m;
  }
  std::shuffle(keyed.begin(), keyed.begin() + m, rng);
  std::stable_sort(keyed.begin(), keyed.begin() + m);
  for (int k = 0; k < m; ++k) {  // the cost orders the operations as the list does, for the score
    cand[k] = found[keyed[k].second];
    cand[k].cost = cand[k].cost * kMaxOps + k;
  }
  op_cand_n_[ai] = m;
}

// Every agent's operations (order_operations), the two halves of the call's agents listed at once
// with search_threads > 1: with 10,000 agents the lists take 20 ms on one thread, most of the
// first pass, and their row reads miss the cache. Each half breaks its ties with its own generator,
// seeded from rng_ either way, so the lists do not depend on the threads.
void PibtStep::list_operations(const WorldView& world) {
  std::mt19937_64 rng[2] = {std::mt19937_64(rng_()), std::mt19937_64(rng_())};
  const size_t half = order_.size() / 2;
  auto list = [&](int h) {
    const size_t from = h == 0 ? 0 : half, to = h == 0 ? half : order_.size();
    for (size_t r = from; r < to; ++r) order_operations(world, order_[r], rng[h]);
  };
  both(opt_.search_threads > 1 && order_.size() >= kParallelListing, [&] { list(0); }, [&] { list(1); });
}

// ai's operation `code` in its list (order_operations); waiting when it is not there.
const PibtStep::OpChoice& PibtStep::listed(int ai, int code) const {
  const OpChoice* cand = &op_cand_[size_t(ai) * kMaxOps];
  const OpChoice* wait = nullptr;
  for (int k = 0; k < op_cand_n_[ai]; ++k) {
    if (cand[k].code == code) return cand[k];
    if (cand[k].code == kWww) wait = &cand[k];
  }
  return *wait;
}

// The swap over operations (rotation_swap_wait; LaCAM*'s swap, as over cells): an agent that has
// stood long, whose best operation enters the cell of an agent that must get past it
// (swap_partner), retreats. Its operations that leave its cell without entering that one come
// first, the earliest to leave first; the other agent, built later, follows through the cell it
// leaves. It goes on while the other still needs it.
void PibtStep::retreat_operations(const WorldView& world, int ai) {
  if (!swap_allowed(world, ai) || world.is_immovable(ai)) return;
  OpChoice* cand = &op_cand_[size_t(ai) * kMaxOps];
  const Cell here = world.positions[ai];
  Cell best = here;
  for (int k = 1; k <= kOpSteps && best == here; ++k) best = cand[0].path.cell[k];
  const int partner = swap_partner(world, ai, best);
  swapping_[ai] = partner >= 0;
  if (partner < 0) return;
  auto leaves = [&](const OpChoice& c) {  // the step c leaves `here` for another cell than `best`
    for (int k = 1; k <= kOpSteps; ++k)
      if (c.path.cell[k] != here) return c.path.cell[k] == best ? kOpSteps + 1 : k;
    return kOpSteps + 1;
  };
  std::stable_sort(cand, cand + op_cand_n_[ai], [&](const OpChoice& a, const OpChoice& b) { return leaves(a) < leaves(b); });
  ++swaps_;
}

bool PibtStep::past_deadline(long& counter) const {
  return deadline_ != std::chrono::steady_clock::time_point::max() && (counter++ & 3) == 0 &&
         std::chrono::steady_clock::now() >= deadline_;
}

// Whether p lies in zone z: only such operations are taken, and only agents holding one displaced,
// so two zones at least kOpSteps + 1 apart never touch the same cell or agent.
bool PibtStep::zone_holds(const OpZone& z, const OpPath& p) const {
  if (z.id == 0) return true;
  for (int k = 0; k <= kOpSteps; ++k)
    if (op_zone_[p.cell[k]] != z.id) return false;
  return true;
}

// Whether every operation from cell c lies in zone z: c is more than kOpSteps cells inside it
// along its axis (an operation moves at most one cell an action). Then build skips zone_holds.
bool PibtStep::deep_in(const OpZone& z, Cell c) const {
  if (z.id == 0) return true;
  const int v = z.axis == 0 ? grid_.x_of(c) : grid_.y_of(c);
  return (z.lo == INT_MIN || v - kOpSteps >= z.lo) && (z.hi == INT_MAX || v + kOpSteps <= z.hi);
}

// EPIBT's build: ai (its path released by the caller) takes its best operation that is free, or
// that displaces one agent of lower priority than the root (`root`, its op_key_) which can in turn
// be built around it (recursively), all within zone z. In the search the result stands only if
// the fleet's score (z.score, its change in the zone) did not fall. Every agent holds a valid
// operation throughout: a failed attempt restores what it changed.
PibtStep::OpResult PibtStep::build(const WorldView& world, int ai, bool search, double root, int depth,
                                   long& counter, OpZone& z) {
  if (past_deadline(counter)) return OpResult::kRejected;
  if (op_[ai].visit != z.round) op_[ai].visit = z.round, op_[ai].visits = 0;
  ++op_[ai].visits;
  op_[ai].on_stack = 1;
  const OpChoice old = op_[ai].held;
  const OpChoice* cand = &op_cand_[size_t(ai) * kMaxOps];
  const bool deep = deep_in(z, world.positions[ai]);
  for (int c = 0; c < op_cand_n_[ai]; ++c) {
    if (!deep && !zone_holds(z, cand[c].path)) continue;
    const int u = blocker(ai, cand[c].path);
    if (u == kBlocked) continue;
    if (u == kFree) {
      op_[ai].held = cand[c];
      reserve(ai, z.score);
      if (search && z.score < z.before - 1e-9) {
        release(ai, z.score);
        op_[ai].held = old;
        op_[ai].on_stack = 0;
        return OpResult::kRejected;
      }
      op_[ai].on_stack = 0;
      return OpResult::kAccepted;
    }
    if (depth >= kOpDepth || op_[u].on_stack || world.is_immovable(u) ||
        (op_[u].visit == z.round && op_[u].visits >= kOpVisits) || op_key_[u] >= root ||
        !zone_holds(z, op_[u].held.path))
      continue;
    release(u, z.score);
    op_[ai].held = cand[c];
    reserve(ai, z.score);
    ++counter;
    const OpResult r = build(world, u, search, root, depth + 1, counter, z);
    if (r == OpResult::kAccepted) {
      op_[ai].on_stack = 0;
      return r;
    }
    release(ai, z.score);
    reserve(u, z.score);  // u's failed build left it holding its own operation
    op_[ai].held = old;
    if (r == OpResult::kRejected) {
      op_[ai].on_stack = 0;
      return r;
    }
  }
  op_[ai].on_stack = 0;
  return OpResult::kFailed;
}

void PibtStep::rebuild(const WorldView& world, int ai, bool search, OpZone& z) {
  long counter = 0;
  z.before = z.score;
  release(ai, z.score);
  if (build(world, ai, search, op_key_[ai], 0, counter, z) != OpResult::kAccepted) reserve(ai, z.score);
}

// Agent ai's operation at the start of the call: the one it chose at the last step, carried on,
// when it made that operation's first action; else wait, wait, wait.
void PibtStep::start_operation(const WorldView& world, int ai) {
  const Pose p = world.pose(ai);
  const OpChoice& last = op_[ai].held;
  const bool carried = op_held_t_[ai] == world.timestep - 1 && last.path.cell[1] == p.cell &&
                       last.path.heading[1] == p.heading && !world.is_immovable(ai);
  op_[ai].held = listed(ai, carried ? carried_code(last.code) : kWww);
}

// Agent ai and, recursively, every agent whose reserved cells meet its own, fall back to waiting.
void PibtStep::wait_in_place(const WorldView& world, int ai) {
  const OpChoice& c = listed(ai, kWww);
  op_[ai].held = c;
  for (int k = 1; k <= kOpSteps; ++k) {
    const int v = res(k, c.path.cell[k]);
    if (v >= 0 && v != ai) {
      release(v, op_score_);
      wait_in_place(world, v);
    }
  }
  reserve(ai, op_score_);
}

// The first pass: the agents built in priority order until the deadline, the rest keeping the
// operation they hold. Its time since `start` (kAuto; the building loop scaled up to the whole
// call when the deadline cut it short, the setup before it not) is smoothed over the calls (one
// slow step should not change the way). A loop cut after a few agents (one long chain of builds)
// shows that the pass needs more than the time it had, not fleet / reached times more: the scale
// is at most kOpCutScale (else one such call rules operations out for thousands of steps). A call
// whose deadline passed before the loop began needs more than its setup: kOpCutScale times it
// (measuring nothing kept auto over operations at 10 ms on warehouse_large, whose setup alone
// takes 20-30 ms).
double PibtStep::first_pass_estimate(double setup, double loop, size_t fleet, size_t reached) {
  if (reached >= fleet) return setup + loop;
  if (reached == 0) return kOpCutScale * (setup + loop);
  return setup + std::min(loop * static_cast<double>(fleet) / static_cast<double>(reached), kOpCutScale * loop);
}

void PibtStep::first_pass(const WorldView& world, std::chrono::steady_clock::time_point start) {
  OpZone map;
  map.round = ++op_round_;
  const auto loop = std::chrono::steady_clock::now();
  size_t reached = 0;  // agents of the priority order the first pass got to
  for (int i : order_) {
    if (std::chrono::steady_clock::now() >= deadline_) {  // the rest: take_free_operations
      ++deadline_stops_;
      break;
    }
    ++reached;
    if (op_[i].visit != op_round_ && !world.is_immovable(i)) rebuild(world, i, false, map);
  }
  op_score_ += map.score;
  if (reached < order_.size()) take_free_operations(world, reached);
  using Seconds = std::chrono::duration<double>;
  const double setup = Seconds(loop - start).count(), pass = Seconds(std::chrono::steady_clock::now() - loop).count();
  double whole = first_pass_estimate(setup, pass, order_.size(), reached);
  // Cut by the deadline, the pass also needed the time the step spent before this call (auto
  // weighs it against the step's whole time: see over_operations).
  if (reached < order_.size() && step_start_ < start) whole += Seconds(start - step_start_).count();
  op_pass_s_ = op_pass_s_ > 0 ? op_pass_s_ + kOpPassWeight * (whole - op_pass_s_) : whole;
}

// A first pass cut by its deadline: each agent it did not reach, in priority order, takes the
// first of its kFreeTries best operations that meets nobody's reserved cells and costs less than
// the one it holds, displacing nobody (up to the hard limit, if any). The order puts the agents
// farthest from their goals last, so without this, when every pass is cut (10,000 agents at 20-30
// ms), the same agents hold their waits step after step and the fleet jams around them.
void PibtStep::take_free_operations(const WorldView& world, size_t from) {
  using Clock = std::chrono::steady_clock;
  for (size_t r = from; r < order_.size(); ++r) {
    const int i = order_[r];
    if ((r - from) % kDeadlineStride == 0 && limit_ != Clock::time_point::max() && Clock::now() >= limit_) break;
    if (op_[i].visit == op_round_ || world.is_immovable(i)) continue;
    const OpChoice* cand = &op_cand_[size_t(i) * kMaxOps];
    const int tries = std::min(op_cand_n_[i], kFreeTries);
    for (int c = 0; c < tries && cand[c].cost < op_[i].held.cost; ++c) {
      if (blocker(i, cand[c].path) != kFree) continue;
      release(i, op_score_);
      op_[i].held = cand[c];
      reserve(i, op_score_);
      ++free_takes_;
      break;
    }
  }
}

// One round of the search in zone z: its agents rebuilt in random order, each change kept when
// the fleet's score does not fall.
void PibtStep::search_round(const WorldView& world, OpZone& z) {
  std::shuffle(z.agents.begin(), z.agents.end(), z.rng);
  for (int i : z.agents) {
    if (std::chrono::steady_clock::now() >= deadline_) break;
    if (op_[i].visit != z.round && !world.is_immovable(i) && zone_holds(z, op_[i].held.path))
      rebuild(world, i, true, z);
  }
}

// A round in two zones at once: the map cut across `axis` (0: x, 1: y) at the agents' median, the
// kOpSteps cells around the cut in neither zone, so that no operation lies in both and each zone's
// thread touches only its own cells and agents. The agents whose operation meets the cut wait for
// a round across the other axis.
void PibtStep::search_zones(const WorldView& world, int axis) {
  if (order_.empty()) return;
  auto along = [&](Cell c) { return axis == 0 ? grid_.x_of(c) : grid_.y_of(c); };
  std::vector<int> at;
  at.reserve(order_.size());
  for (int i : order_) at.push_back(along(world.positions[i]));
  std::nth_element(at.begin(), at.begin() + at.size() / 2, at.end());
  const int below = at[at.size() / 2] - 1 - kOpSteps / 2, above = below + kOpSteps + 1;
  op_zone_.resize(grid_.num_cells());
  for (Cell c = 0; c < grid_.num_cells(); ++c) {
    const int v = along(c);
    op_zone_[c] = v <= below ? 1 : v >= above ? 2 : 0;
  }
  OpZone zones[2];
  for (int k = 0; k < 2; ++k) zones[k].id = k + 1, zones[k].round = ++op_round_, zones[k].rng.seed(rng_());
  for (OpZone& z : zones) z.axis = axis;
  zones[0].hi = below, zones[1].lo = above;
  for (int i : order_)
    for (OpZone& z : zones)
      if (zone_holds(z, op_[i].held.path)) z.agents.push_back(i);
  ++op_zoned_rounds_;
  both(true, [&] { search_round(world, zones[0]); }, [&] { search_round(world, zones[1]); });
  op_score_ += zones[0].score + zones[1].score;
}

// EPIBT's LNS until the deadline: agents rebuilt in random order, each change kept when the
// fleet's score does not fall, until a round gains nothing. With search_threads the rounds run in
// two zones at once, across x and y in turn, until two rounds in a row gain nothing; then over the
// whole map (for the chains across the cuts) until a round gains nothing.
void PibtStep::search_operations(const WorldView& world) {
  bool zoned = opt_.search_threads > 1;
  OpZone whole;
  whole.agents = order_;
  whole.rng.seed(rng_());
  for (int idle = 0, round = 0; std::chrono::steady_clock::now() < deadline_; ++round) {
    const double before = op_score_;
    ++op_search_rounds_;
    if (zoned) {
      search_zones(world, round % 2);
    } else {
      whole.round = ++op_round_, whole.score = 0;
      search_round(world, whole);
      op_score_ += whole.score;
    }
    if (op_score_ > before + 1e-9) idle = 0;
    else if (!zoned) break;
    else if (++idle == 2) zoned = false;
  }
}

// The tables of the calls over operations, for n agents (kept, grown when a call has more).
void PibtStep::size_operations(int n) {
  res_.resize(size_t(kOpSteps) * grid_.num_cells(), kFree);
  if (static_cast<int>(op_.size()) < n) {
    op_.resize(n), op_held_t_.resize(n, INT_MIN), op_wait_cost_.resize(n), op_power_.resize(n);
    op_key_.resize(n), op_cand_.resize(size_t(n) * kMaxOps), op_cand_n_.resize(n);
  }
}

// The step in the rotation model (EPIBT): every agent of the call starts holding the operation it
// carried on from the last step (or waits), the agents are built in priority order, and with a
// deadline the rest of the time goes to rebuilding agents in random order, keeping each change
// that does not lower the fleet's score (the sum over agents of the cost they gain over waiting,
// weighted by their priority's rank). Each agent's first action is its move.
void PibtStep::plan_operations(const WorldView& world, std::vector<Cell>& next,
                               const std::vector<std::pair<Cell, Cell>>& fixed_moves) {
  const auto start = std::chrono::steady_clock::now();
  const int n = world.num_agents();
  size_operations(n);
  auto fix = [&](Cell c, int from_k) {
    for (int k = from_k; c != kNoCell && k <= kOpSteps; ++k) res(k, c) = kFixed;
  };
  for (auto& [from, to] : fixed_moves) {
    if (from != kNoCell) res(1, from) = kFixed;
    fix(to, 1);
  }
  if (world.blocked)
    for (Cell c : *world.blocked) fix(c, 1);
  // Priority: EPIBT's, the nearest to its goal first (ties by PIBT's priority), and agents whose
  // goal is their own cell (none, or waiting: dead_end_wait) last, so others may displace them;
  // the weight of an agent in the score falls with its rank.
  list_operations(world);
  for (int i : order_) {
    retreat_operations(world, i);
    op_wait_cost_[i] = listed(i, kWww).cost;
    const bool idle = goal_of_[i] == world.positions[i];  // no goal, or waiting (dead_end_wait)
    op_key_[i] = (idle ? -1e9 : -static_cast<double>(op_wait_cost_[i] / kMaxOps)) + 1e-6 * priority_[i];
  }
  std::stable_sort(order_.begin(), order_.end(), [&](int a, int b) { return op_key_[a] > op_key_[b]; });
  const double m = static_cast<double>(order_.size()) + 1;
  for (size_t r = 0; r < order_.size(); ++r) {
    const double power = (m - static_cast<double>(r)) / m;
    op_power_[order_[r]] = power * power;
  }
  op_score_ = 0;
  for (int i : order_) {
    start_operation(world, i);
    if (blocker(i, op_[i].held.path) != kFree) wait_in_place(world, i);
    else reserve(i, op_score_);
  }
  first_pass(world, start);
  if (deadline_ != std::chrono::steady_clock::time_point::max()) search_operations(world);
  for (int i : order_) {
    const OpPath& p = op_[i].held.path;
    next[i] = p.cell[1];
    (*world.next_headings)[i] = p.heading[1];
    op_held_t_[i] = world.timestep;  // the next step carries it on (start_operation)
    for (int k = 1; k <= kOpSteps; ++k) res(k, p.cell[k]) = kFree;
  }
  for (auto& [from, to] : fixed_moves)
    for (Cell c : {from, to})
      for (int k = 1; c != kNoCell && k <= kOpSteps; ++k) res(k, c) = kFree;
  if (world.blocked)
    for (Cell c : *world.blocked)
      for (int k = 1; k <= kOpSteps; ++k) res(k, c) = kFree;
}

}  // namespace gdrhcr
