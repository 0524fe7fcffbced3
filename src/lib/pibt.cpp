#include "gdrhcr/pibt.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "gdrhcr/mapf_in_rotation.hpp"
#include "gdrhcr/task_stream.hpp"

namespace gdrhcr {

namespace {
constexpr int kFree = -1;
constexpr int kFixed = -2;  // a cell held by an agent PIBT does not move this call
}  // namespace

PibtStep::PibtStep(const Grid& grid, int num_agents, uint64_t seed, PibtOptions options)
    : grid_(grid),
      opt_(options),
      rng_(mix_seed(seed, 0x50494254ULL)),
      priority_(num_agents),
      last_goal_(num_agents, kNoCell),
      occupied_now_(grid.num_cells(), kFree),
      occupied_next_(grid.num_cells(), kFree),
      rows_(num_agents),
      row_goal_(num_agents, kNoCell),
      goal_of_(num_agents, kNoCell) {
  std::uniform_real_distribution<double> tie(0.0, 1.0);
  for (auto& p : priority_) p = tie(rng_);
  // kAuto times its first pass over operations: the tables are made (and their pages touched)
  // here, so that no call's first pass pays for them (on warehouse_large 80 ms of setup at the
  // first call against 25-30 later).
  if (opt_.rotation == PibtOptions::Rotation::kAuto) size_operations(num_agents);
}

// Priority = time since the agent last reached a goal, plus its fixed tie-breaker in [0, 1).
// Reaching a goal shows as standing on it, or (lifelong runs, where the next goal is handed out
// before the next call) as the goal having changed since the agent's last update.
void PibtStep::update_priority(const WorldView& world, int i, Cell goal) {
  const bool reached = world.positions[i] == goal ||
                       (opt_.priority_reset && last_goal_[i] != kNoCell && last_goal_[i] != goal);
  if (reached) priority_[i] -= std::floor(priority_[i]);
  else priority_[i] += 1.0;
  last_goal_[i] = goal;
}

// The goal PIBT moves agent i towards now: its own cell while it waits to set out for a dead end
// (dead_end_wait, dead_end_parked), else its goal.
Cell PibtStep::goal_now(const WorldView& world, int i) {
  const Cell here = world.positions[i];
  const Cell g = world.goals[i].empty() ? here : world.goals[i][0];
  if (opt_.dead_end_wait <= 0 || g == here) return g;
  const auto nb = grid_.neighbours(g);
  if (nb.end() - nb.begin() > 1) return g;
  if (waited_for_.size() < priority_.size())
    waited_for_.resize(priority_.size(), kNoCell), wait_until_.resize(priority_.size(), 0),
        set_out_.resize(priority_.size(), 0);
  if (waited_for_[i] != g) waited_for_[i] = g, wait_until_[i] = world.timestep + opt_.dead_end_wait, set_out_[i] = 0;
  const bool waits = world.timestep < wait_until_[i] || (opt_.dead_end_parked > 0 && !set_out_[i]);
  return waits ? here : g;
}

// dead_end_parked: while more agents wait for a dead end than it allows, those past their
// dead_end_wait set out, the one that has waited longest first.
void PibtStep::end_dead_end_waits(const WorldView& world) {
  if (opt_.dead_end_wait <= 0 || opt_.dead_end_parked <= 0) return;
  int waiting = 0;
  std::vector<std::pair<int, int>> past;  // (end of the wait, agent)
  for (int k = 0; k < static_cast<int>(waited_for_.size()); ++k) {
    if (set_out_[k] || waited_for_[k] == kNoCell || world.goals[k].empty() || world.goals[k][0] != waited_for_[k])
      continue;
    ++waiting;
    if (world.timestep >= wait_until_[k]) past.emplace_back(wait_until_[k], k);
  }
  std::sort(past.begin(), past.end());
  for (size_t j = 0; j < past.size() && waiting > opt_.dead_end_parked; ++j, --waiting) set_out_[past[j].second] = 1;
}

// rotation_commit: while the configuration chosen earlier is not reached (and for at most three
// steps), this step carries on towards it instead of planning a new one; a new configuration
// becomes the target. Only for a call that moves the whole fleet (order_ holds every agent), with
// nothing fixed or blocked.
// Returns true when `next` holds the step carried on.
bool PibtStep::carry_on(const WorldView& world, std::vector<Cell>& next,
                        const std::vector<std::pair<Cell, Cell>>& fixed_moves) {
  const int n = world.num_agents();
  const bool whole = opt_.rotation_commit && world.rotation() && static_cast<int>(order_.size()) == n &&
                     fixed_moves.empty() && !world.immovable && !(world.blocked && !world.blocked->empty());
  if (!whole) {
    target_steps_ = 0;
    return false;
  }
  bool going = target_steps_ > 0 && target_steps_ < 3 && static_cast<int>(target_.size()) == n;
  bool arrived = true;
  for (int i = 0; going && i < n; ++i) {  // every agent where the plan left it: its origin or its cell
    arrived = arrived && world.positions[i] == target_[i];
    going = world.positions[i] == target_[i] || world.positions[i] == origin_[i];
  }
  if (!going || arrived) {  // plan a new configuration
    choose_configuration(world, next);
    target_.assign(next.begin(), next.begin() + n);
    origin_ = world.positions;
    target_steps_ = 0;
  } else {
    for (int i : order_) occupied_now_[world.positions[i]] = kFree;
    std::copy(target_.begin(), target_.end(), next.begin());
  }
  ++target_steps_;
  execute_with_turns(world, next);
  return true;
}

// rotation_starts (see PibtOptions): the best of several PIBT runs becomes the configuration.
// Called by carry_on for the whole fleet, with nothing fixed, immovable or blocked.
void PibtStep::choose_configuration(const WorldView& world, std::vector<Cell>& next) {
  using Clock = std::chrono::steady_clock;
  if (opt_.rotation_starts <= 1) {
    push_all(world, next, {});
    ++starts_;
    return;
  }
  const std::vector<double> base = priority_;
  std::mt19937_64 shake(rng_());
  const std::mt19937_64 rng_at_start = rng_;
  std::vector<Cell> best;
  long best_gain = std::numeric_limits<long>::min();
  int winner = 0;
  Clock::duration slowest{0};
  for (int k = 0; k < opt_.rotation_starts; ++k) {
    const auto t0 = Clock::now();
    if (k > 0) {
      if (deadline_ - t0 < slowest) break;
      shake_box(world, base, shake);
      for (int i : order_) occupied_now_[world.positions[i]] = i, next[i] = kNoCell;
      rng_ = rng_at_start;
    }
    push_all(world, next, {});
    ++starts_;
    const long gain = distance_gain(world, next);
    if (gain > best_gain) best_gain = gain, best.assign(next.begin(), next.end()), winner = k;
    slowest = std::max(slowest, Clock::now() - t0);
  }
  starts_won_ += winner > 0;
  priority_ = base;
  std::copy(best.begin(), best.end(), next.begin());
}

// The priorities of one run: `base`, raised at random by up to kStartNoise for the agents within
// kStartBox cells (each way) of a random agent's cell.
void PibtStep::shake_box(const WorldView& world, const std::vector<double>& base, std::mt19937_64& shake) {
  priority_ = base;
  const int w = grid_.width();
  const Cell centre = world.positions[order_[shake() % order_.size()]];
  std::uniform_real_distribution<double> noise(0.0, kStartNoise);
  for (int i : order_) {
    const Cell c = world.positions[i];
    if (std::abs(c % w - centre % w) <= kStartBox && std::abs(c / w - centre / w) <= kStartBox)
      priority_[i] += noise(shake);
  }
}

// How much nearer their goals the cells in `next` bring the agents (distance with turns, from the
// heading of the move), summed over the agents of this call.
long PibtStep::distance_gain(const WorldView& world, const std::vector<Cell>& next) const {
  long gain = 0;
  for (int i : order_) {
    const Cell here = world.positions[i];
    gain += std::min(near(i, here, here), 1 << 24) - std::min(near(i, here, next[i]), 1 << 24);
  }
  return gain;
}

// rotation_keep: the preferred cells of this call, each agent's kept cell where the caller gives
// none. A cell is kept for the next step only, by an agent still in the same cell with the same
// goal, and not while the agent may swap (its retreat must not be taken for its goal).
const std::vector<Cell>* PibtStep::with_kept_cells(const WorldView& world, const std::vector<Cell>* preferred) {
  const size_t n = world.num_agents();
  if (kept_.size() < n)
    kept_.resize(n, kNoCell), kept_from_.resize(n, kNoCell), kept_goal_.resize(n, kNoCell),
        kept_t_.resize(n, std::numeric_limits<int>::min()), kept_pref_.resize(n, kNoCell);
  for (int i : order_) {
    const Cell given = preferred ? (*preferred)[i] : kNoCell;
    const bool keep = kept_t_[i] == world.timestep - 1 && kept_from_[i] == world.positions[i] &&
                      kept_goal_[i] == goal_of_[i] && !swap_allowed(world, i);
    kept_pref_[i] = given != kNoCell ? given : keep ? kept_[i] : kNoCell;
  }
  return &kept_pref_;
}

// After the step is executed with turns: of the cells PIBT chose (in kept_ since before the
// execution), those agents did not get to.
void PibtStep::keep_unreached_cells(const WorldView& world, const std::vector<Cell>& next) {
  for (int i : order_) {
    const Cell c = kept_[i];
    kept_[i] = c != world.positions[i] && next[i] != c ? c : kNoCell;
    kept_from_[i] = world.positions[i];
    kept_goal_[i] = goal_of_[i];
    kept_t_[i] = world.timestep;
  }
}

// Steps the agent has stood in its cell; a second call in the same timestep changes nothing.
void PibtStep::update_standing(const WorldView& world, int i) {
  if (standing_t_[i] == world.timestep) return;
  const bool stood = standing_at_[i] == world.positions[i] && standing_t_[i] == world.timestep - 1;
  standing_[i] = stood ? standing_[i] + 1 : 0;
  standing_at_[i] = world.positions[i];
  standing_t_[i] = world.timestep;
}

// The swap: in the mapf model always (when on); in the rotation model for an agent that has stood
// in its cell rotation_swap_wait steps, and then until its partner no longer needs it.
bool PibtStep::swap_allowed(const WorldView& world, int ai) const {
  if (!opt_.swap) return false;
  if (!world.rotation()) return true;
  return opt_.rotation_swap_wait > 0 && (swapping_[ai] || standing_[ai] >= opt_.rotation_swap_wait);
}

void PibtStep::step(const WorldView& world, std::vector<Cell>& next, const std::vector<int>& agents,
                    const std::vector<std::pair<Cell, Cell>>& fixed_moves,
                    const std::vector<Cell>* preferred) {
  const int n = world.num_agents();
  if (static_cast<int>(priority_.size()) < n) {
    std::uniform_real_distribution<double> tie(0.0, 1.0);
    while (static_cast<int>(priority_.size()) < n) priority_.push_back(tie(rng_));
    rows_.resize(n);
    row_goal_.resize(n, kNoCell);
    goal_of_.resize(n, kNoCell);
    last_goal_.resize(n, kNoCell);
  }
  if (static_cast<int>(standing_.size()) < n)
    standing_.resize(n, 0), standing_at_.resize(n, kNoCell), standing_t_.resize(n, std::numeric_limits<int>::min()),
        swapping_.resize(n, 0);
  preferred_ = preferred;
  immovable_ = world.immovable;
  if (table_id_ != world.dist.id()) {  // rows kept from another table: drop them
    for (auto& r : rows_) r.reset();
    std::fill(row_goal_.begin(), row_goal_.end(), kNoCell);
    table_id_ = world.dist.id();
  }
  order_.clear();
  if (agents.empty()) {
    order_.resize(n);
    std::iota(order_.begin(), order_.end(), 0);
  } else {
    order_ = agents;
  }
  end_dead_end_waits(world);
  for (size_t k = 0; k < order_.size(); ++k) {
    const int i = order_[k];
    if (k + kNearAhead < order_.size())  // each agent's goal list is a cache miss of its own
      __builtin_prefetch(world.goals[order_[k + kNearAhead]].data());
    const Cell g = goal_now(world, i);
    update_priority(world, i, g);
    if (world.rotation()) update_standing(world, i);  // only the rotation model's swap reads it
    goal_of_[i] = g;
    if (row_goal_[i] != g) rows_[i] = world.dist.row(g), row_goal_[i] = g;
    occupied_now_[world.positions[i]] = i;
    next[i] = kNoCell;
  }
  const bool operations = over_operations(world);
  if (!operations) near_distances(world);
  if (operations) {
    plan_operations(world, next, fixed_moves);
    for (int i : order_) occupied_now_[world.positions[i]] = kFree;
  } else if (!carry_on(world, next, fixed_moves)) {
    const bool keep = opt_.rotation_keep && world.rotation();
    if (keep) preferred_ = with_kept_cells(world, preferred);
    push_all(world, next, fixed_moves);
    if (world.rotation()) {
      if (keep)
        for (int i : order_) kept_[i] = next[i];  // the chosen cells, until keep_unreached_cells
      execute_with_turns(world, next);
      if (keep) keep_unreached_cells(world, next);
    }
  }
  preferred_ = nullptr;
  immovable_ = nullptr;
  deadline_ = step_start_ = limit_ = std::chrono::steady_clock::time_point::max();
  near_cut_ = false;
}

// Over operations: more than half of this call's agents have stood kStallSteps steps or more (a
// jam operations do not get out of); the call is planned over cells instead.
bool PibtStep::stalled() {
  size_t stood = 0;
  for (int i : order_) stood += standing_[i] >= kStallSteps;
  const bool stall = stood * 2 > order_.size();
  stalls_ += stall;
  return stall;
}

// Whether this call plans over operations (see PibtOptions::Rotation): kOperations unless stalled,
// kAuto when also the deadline leaves the search room (kOpRoom, measured from the caller's step
// start when given: what the solves before PIBT take varies with the way, and over cells it left
// too little to come back to operations on warehouse_large; a call after one over operations
// stays with them down to kOpStay, so that the way does not change at every step when the room is
// near the bound). The first pass's time is known from the calls over operations; each call over
// cells lowers it by kOpRetry, so that operations are tried again now and then (a first call,
// computing rows, or a slow step does not rule them out for good; a change of way costs the fleet
// a step or two, so seldom). Retries that do not fit back off (OpRetry): while a wait holds, the
// estimate is not lowered, so only a deadline with room for it brings operations back. A first
// pass the deadline cut counts the step's time before the call in its estimate: where guidance
// takes most of the step, passes that never end would otherwise be weighed against the whole
// step and kept (random-64-64-20, 1,600 agents at 50 ms: docs/results.md, "Session 48").
bool PibtStep::over_operations(const WorldView& world) {
  using Clock = std::chrono::steady_clock;
  if (!world.rotation() || opt_.rotation == PibtOptions::Rotation::kCells) return false;
  if (opt_.rotation == PibtOptions::Rotation::kAuto) {
    const double room = op_auto_ ? kOpStay : kOpRoom;
    const Clock::time_point from = step_start_ != Clock::time_point::max() ? step_start_ : Clock::now();
    const double have =
        deadline_ != Clock::time_point::max() ? std::chrono::duration<double>(deadline_ - from).count() : -1;
    const bool was = op_auto_;
    op_auto_ = have >= room * op_pass_s_;
    if (!op_auto_) {
      if (was) op_retry_.left();
      if (!op_retry_.holding()) op_pass_s_ *= kOpRetry;
      op_retry_.tick();
      return false;
    }
    op_retry_.over_operations();
  }
  if (stalled()) return false;
  ++op_calls_;
  return true;
}

void PibtStep::OpRetry::left() {
  backoff = streak >= kShortSeries ? 0 : backoff == 0 ? kFirstHold : std::min(2 * backoff, kMaxHold);
  hold = backoff;
  streak = 0;
}

// The mapf step (and the rotation model's kCells): immovable agents, fixed moves and blocked
// cells taken first, then one push per agent in priority order; the scratch tables are left clean.
void PibtStep::push_all(const WorldView& world, std::vector<Cell>& next,
                        const std::vector<std::pair<Cell, Cell>>& fixed_moves) {
  // Immovable agents stay, and so do the agents whose distances were not read (near_distances
  // stopped at the hard limit): their cell is taken for t+1, so nobody pushes them or moves in.
  if (world.immovable || near_cut_)
    for (int i : order_)
      if ((world.immovable && (*world.immovable)[i]) ||
          (near_cut_ && near_[static_cast<size_t>(i) * kNear + kNumHeadings] == kNotRead))
        next[i] = world.positions[i], occupied_next_[world.positions[i]] = i;
  // Agents outside this call keep their moves; their cells at t and t+1 are off limits, which
  // rules out both vertex and swap conflicts with them.
  for (auto& [from, to] : fixed_moves) {
    if (from != kNoCell) occupied_next_[from] = kFixed;
    if (to != kNoCell) occupied_next_[to] = kFixed;
  }
  if (world.blocked)  // blocked cells (a late robot still leaving them): nobody enters
    for (Cell c : *world.blocked) occupied_next_[c] = kFixed;
  sort_by_priority();
  // A call that begins past its deadline plans everyone, up to the hard limit if there is one: the
  // step is over its budget whatever PIBT does, and stopping at once would leave all but
  // kDeadlineStride agents to step ahead or wait.
  using Clock = std::chrono::steady_clock;
  const Clock::time_point stop = Clock::now() < deadline_ ? std::min(deadline_, limit_) : limit_;
  const bool timed = stop != Clock::time_point::max();
  // The stop leaves room for the cheap steps of the agents not reached (ahead_s_ each, measured).
  for (size_t k = 0; k < order_.size(); ++k) {
    if (timed && k >= kDeadlineStride && k % kDeadlineStride == 0 &&
        Clock::now() + std::chrono::duration_cast<Clock::duration>(
                           std::chrono::duration<double>(double(order_.size() - k) * ahead_s_)) >= stop) {
      ++deadline_stops_;  // the agents no push has reached take a cheap step
      const auto cut = Clock::now();
      const size_t rest = order_.size() - k;
      for (; k < order_.size(); ++k)
        if (next[order_[k]] == kNoCell) step_ahead(world, order_[k], next);
      ahead_s_ = std::chrono::duration<double>(Clock::now() - cut).count() / double(rest);
      break;
    }
    if (next[order_[k]] == kNoCell) push(world, order_[k], -1, next);
  }
  pushed_at_ = Clock::now();
  // Reset the scratch tables touched this call, so the next call starts clean in O(agents).
  for (int i : order_) {
    occupied_now_[world.positions[i]] = kFree;
    occupied_next_[next[i]] = kFree;
  }
  for (auto& [from, to] : fixed_moves) {
    if (from != kNoCell) occupied_next_[from] = kFree;
    if (to != kNoCell) occupied_next_[to] = kFree;
  }
  if (world.blocked)
    for (Cell c : *world.blocked) occupied_next_[c] = kFree;
}

// Each agent's distance from its cell (rotation: facing its heading) and from each 4-neighbour
// (facing the way the move there leaves it), read from its row once per call, in one pass that
// fetches the rows of the agents kNearAhead and 2 x kNearAhead further on (the row object, then the
// entries around the cell). With thousands of agents every row read is a cache miss; taken one at
// a time, inside the pushes, they were most of PIBT's time.
void PibtStep::near_distances(const WorldView& world) {
  if (near_.size() < priority_.size() * kNear) near_.resize(priority_.size() * kNear);
  const bool rot = world.rotation();
  const size_t n = order_.size();
  const int w = grid_.width();
  // Under a hard limit the reads stop where the rest of it would no longer cover every agent's
  // cheap step (ahead_s_ each, measured at the last stop of push_all): on a machine that slows
  // memory reads fourfold in bursts, reading 10,000 agents' rows alone can take the whole budget.
  using Clock = std::chrono::steady_clock;
  const bool timed = limit_ != Clock::time_point::max();
  const auto cheap_steps = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(double(n) * ahead_s_));
  near_cut_ = false;
  for (size_t k = 0; k < n; ++k) {
    if (timed && k >= kDeadlineStride && k % kDeadlineStride == 0 && Clock::now() + cheap_steps >= limit_) {
      for (; k < n; ++k) near_[static_cast<size_t>(order_[k]) * kNear + kNumHeadings] = kNotRead;
      near_cut_ = true;
      ++near_cuts_;
      return;
    }
    if (k + 2 * kNearAhead < n) {
      const char* object = reinterpret_cast<const char*>(rows_[order_[k + 2 * kNearAhead]].get());
      __builtin_prefetch(object);
      __builtin_prefetch(object + 64);
    }
    if (k + kNearAhead < n) {
      const int a = order_[k + kNearAhead];
      const Cell c = world.positions[a];
      rows_[a]->prefetch(c);
      if (c >= w) rows_[a]->prefetch(c - w);
      if (c + w < grid_.num_cells()) rows_[a]->prefetch(c + w);
    }
    const int i = order_[k];
    const DistRow& row = *rows_[i];
    const Cell here = world.positions[i];
    int* d = &near_[static_cast<size_t>(i) * kNear];
    for (Heading h = 0; h < kNumHeadings; ++h) {
      const Cell c = forward_cell(grid_, here, h);
      d[h] = c == kNoCell ? kUnreachable : rot ? row.at(c, h) : row[c];
    }
    d[kNumHeadings] = rot ? row.at(here, (*world.headings)[i]) : row[here];
  }
}

// Agent i's distance from cell c, here or a 4-neighbour of its cell (near_distances).
int PibtStep::near(int i, Cell here, Cell c) const {
  const int* d = &near_[static_cast<size_t>(i) * kNear];
  return c == here ? d[kNumHeadings] : d[heading_of_move(grid_, here, c)];
}

// order_ by priority, highest first, equal priorities in their order (a stable sort, on keys read
// once: with 10,000 agents an indirect comparison costs a cache miss each).
void PibtStep::sort_by_priority() {
  keyed_.resize(order_.size());
  for (size_t k = 0; k < order_.size(); ++k) keyed_[k] = {-priority_[order_[k]], static_cast<int>(k)};
  std::sort(keyed_.begin(), keyed_.end());
  for (size_t k = 0; k < keyed_.size(); ++k) keyed_[k].second = order_[keyed_[k].second];
  for (size_t k = 0; k < keyed_.size(); ++k) order_[k] = keyed_[k].second;
}

// An agent past the deadline: into the cell ahead (rotation: the one it faces; mapf: its nearest
// neighbour) when nobody stands there or has claimed it and it is nearer the goal, else it waits.
// A look at its near distances, against PIBT's candidates and pushes; valid, since the cell is empty now.
void PibtStep::step_ahead(const WorldView& world, int ai, std::vector<Cell>& next) {
  const Cell here = world.positions[ai];
  Cell to = here;
  if (world.rotation()) {
    const Heading h = (*world.headings)[ai];
    const Cell f = forward_cell(grid_, here, h);
    if (f != kNoCell && near(ai, here, f) < near(ai, here, here)) to = f;
  } else {
    int best = near(ai, here, here);
    for (Cell c : grid_.neighbours(here))
      if (near(ai, here, c) < best && occupied_now_[c] == kFree && occupied_next_[c] == kFree)
        best = near(ai, here, c), to = c;
  }
  if (to != here && (occupied_now_[to] != kFree || occupied_next_[to] != kFree)) to = here;
  occupied_next_[to] = ai;
  next[ai] = to;
}

// kCells in the rotation model: the cells this call chose, executed by turning first (see
// PibtOptions::Rotation). Agents outside the call keep out of these agents' cells (fixed moves).
void PibtStep::execute_with_turns(const WorldView& world, std::vector<Cell>& next) const {
  std::vector<Cell> pos, cells;
  std::vector<Heading> heads;
  for (int i : order_) pos.push_back(world.positions[i]), heads.push_back((*world.headings)[i]), cells.push_back(next[i]);
  const std::vector<Action> act = rotation_actions_for_step(grid_, pos, heads, cells);
  for (size_t k = 0; k < order_.size(); ++k) {
    const Pose p = apply_action(grid_, {pos[k], heads[k]}, act[k]);
    next[order_[k]] = p.cell;
    (*world.next_headings)[order_[k]] = p.heading;
  }
}

// kCells in the rotation model: candidates by the distance with turns after the move (from the
// heading it leaves the agent in) plus the quarter turns it takes and the step itself (staying:
// a step), the preferred cell first; among equals the fewest turns, then (kFreeFirst) a cell
// nobody stands on, then at random. Without rotation_commit, a pushed agent pays
// rotation_push_turn_cost more for a cell it must turn towards: it stays this step, and so does its
// pusher.
void PibtStep::order_candidates_with_turns(const WorldView& world, int ai, bool pushed, Cell* cand, int m) {
  const Cell pref = preferred_ ? (*preferred_)[ai] : kNoCell;
  const Pose at = world.pose(ai);
  std::shuffle(cand, cand + m, rng_);
  const bool free_first = opt_.tie_break != PibtOptions::TieBreak::kRandom;
  const int pusher_waits = pushed && !opt_.rotation_commit ? opt_.rotation_push_turn_cost : 0;  // per turning cell
  long long key[5];
  for (int k = 0; k < m; ++k) {
    const Cell c = cand[k];
    const Heading h = c == at.cell ? at.heading : heading_of_move(grid_, at.cell, c);
    const int turns = turn_steps(at.heading, h);
    const long long cost = std::min(near(ai, at.cell, c), 1 << 24) + turns + 1 + (turns > 0 ? pusher_waits : 0);
    key[k] = (c == pref ? 0LL : 1LL << 40) + cost * 8 + turns * 2 + (free_first && occupied_now_[c] != kFree ? 1 : 0);
  }
  for (int k = 1; k < m; ++k)
    for (int j = k; j > 0 && key[j] < key[j - 1]; --j) std::swap(key[j], key[j - 1]), std::swap(cand[j], cand[j - 1]);
}

// Candidates: the neighbours and staying put, the preferred cell first, then nearest to the
// goal; among equals (tie_break kFreeFirst) a cell nobody stands on, then a random order.
void PibtStep::order_candidates(const WorldView& world, int ai, bool pushed, Cell* cand, int m) {
  if (world.rotation()) return order_candidates_with_turns(world, ai, pushed, cand, m);
  const Cell pref = preferred_ ? (*preferred_)[ai] : kNoCell;
  const Cell here = world.positions[ai];
  std::shuffle(cand, cand + m, rng_);
  const bool free_first = opt_.tie_break != PibtOptions::TieBreak::kRandom;
  // A stable insertion sort on keys read once (std::stable_sort allocates a buffer per call).
  int key[5];
  for (int k = 0; k < m; ++k) {
    const Cell c = cand[k];
    key[k] = (c == pref ? 0 : 1 << 30) + std::min(near(ai, here, c), (1 << 24) - 1) * 2 +
             (free_first && occupied_now_[c] != kFree ? 1 : 0);
  }
  for (int k = 1; k < m; ++k)
    for (int j = k; j > 0 && key[j] < key[j - 1]; --j) std::swap(key[j], key[j - 1]), std::swap(cand[j], cand[j - 1]);
}


bool PibtStep::push(const WorldView& world, int ai, int aj, std::vector<Cell>& next) {
  const Cell here = world.positions[ai];
  Cell cand[5];
  int m = 0;
  for (Cell c : grid_.neighbours(here)) cand[m++] = c;
  cand[m++] = here;
  order_candidates(world, ai, aj >= 0, cand, m);
  // Swap: the agent on the best cell must get past this one; walk away and pull it along.
  int partner = -1;
  if (swap_allowed(world, ai)) {
    partner = swap_partner(world, ai, cand[0]);
    if (partner >= 0 && next[partner] != kNoCell) partner = -1;
    if (partner >= 0 && !world.rotation()) std::reverse(cand, cand + m);
    if (partner >= 0 && world.rotation()) retreat_order(here, cand, m);
    if (world.rotation()) swapping_[ai] = partner >= 0;
  }
  for (int k = 0; k < m; ++k) {
    const Cell u = cand[k];
    if (occupied_next_[u] != kFree) continue;
    const int ak = occupied_now_[u];
    // Never swap cells with an agent already moving into ours (the pusher included).
    if (ak >= 0 && ak != ai && (ak == aj || next[ak] == here)) continue;
    occupied_next_[u] = ai;
    next[ai] = u;
    if (ak >= 0 && ak != ai && next[ak] == kNoCell && !push(world, ak, ai, next)) continue;
    // Pull the swap partner into the cell we leave.
    if (partner >= 0 && k == 0 && u != here && next[partner] == kNoCell &&
        occupied_next_[here] == kFree && world.positions[partner] != u) {
      occupied_next_[here] = partner;
      next[partner] = here;
      ++swaps_;
    }
    return true;
  }
  occupied_next_[here] = ai;
  next[ai] = here;
  return false;
}

// The rotation model's swap: retreat into the nearest other cell, staying second to last and the
// best cell last. The mapf model reverses the whole order; here that would flip with each quarter
// turn (the farthest cell changes with the heading) and the agent would turn to and fro.
void PibtStep::retreat_order(Cell here, Cell* cand, int m) const {
  std::rotate(cand, cand + 1, cand + m);  // best last
  std::stable_partition(cand, cand + m - 1, [&](Cell c) { return c != here; });  // here just before it
}

// Cells next to `at` an agent could step aside into, other than `except` (where the other agent
// comes from): not held by an agent outside this call, an immovable agent, or an agent resting
// on its goal at the end of a dead end. Returns their count; *other is one of them.
int PibtStep::passable_neighbours(Cell at, Cell except, Cell* other) const {
  int count = 0;
  for (Cell u : grid_.neighbours(at)) {
    if (u == except || occupied_next_[u] == kFixed) continue;
    const int a = occupied_now_[u];
    if (a >= 0) {
      const auto nb = grid_.neighbours(u);
      if (nb.end() - nb.begin() == 1 && goal_of_[a] == u) continue;
      if (immovable_ && (*immovable_)[a]) continue;
    }
    ++count;
    *other = u;
  }
  return count;
}

// Does the pusher (at pusher_at, heading through puller_at) need to swap with the puller? Walk
// ahead of the pusher while it keeps approaching its goal in a corridor: a junction ahead means
// plain pushing can clear the way; otherwise a swap is needed when the puller wants to come
// towards the pusher's side and the pusher wants to go the other way.
bool PibtStep::needs_swap(Cell pusher_at, Cell puller_at, const DistRow& pusher_row,
                          const DistRow& puller_row) const {
  Cell a = pusher_at, b = puller_at;
  for (int guard = 0; pusher_row[b] < pusher_row[a] && guard < grid_.num_cells(); ++guard) {
    Cell ahead = kNoCell;
    const int room = passable_neighbours(b, a, &ahead);
    if (room >= 2) return false;  // a junction ahead: pushing works
    if (room == 0) break;         // a dead end
    a = b;
    b = ahead;
  }
  return puller_row[a] < puller_row[b] && (pusher_row[a] == 0 || pusher_row[b] < pusher_row[a]);
}

// Can the pusher pull the puller behind it until they reach a junction where they pass? Walk
// backwards from the puller (the agent that retreats) through the corridor behind it.
bool PibtStep::can_swap(Cell pusher_at, Cell puller_at) const {
  const Cell origin = pusher_at;
  Cell a = pusher_at, b = puller_at;
  for (int guard = 0; b != origin && guard < grid_.num_cells(); ++guard) {
    Cell behind = kNoCell;
    const int room = passable_neighbours(b, a, &behind);
    if (room >= 2) return true;
    if (room == 0) return false;
    a = b;
    b = behind;
  }
  return false;
}

// The agent to pull along when `ai` retreats, or -1. Case 1: the agent on ai's best cell must get
// past ai. Case 2 (clearing): a neighbour behind ai must get past it into the corridor ai enters.
int PibtStep::swap_partner(const WorldView& world, int ai, Cell best) const {
  const Cell here = world.positions[ai];
  if (best == here) return -1;
  const int aj = occupied_now_[best];
  if (aj >= 0 && aj != ai && !world.is_immovable(aj) &&
      needs_swap(here, best, *rows_[ai], *rows_[aj]) && can_swap(best, here))
    return aj;
  for (Cell u : grid_.neighbours(here)) {
    const int ak = occupied_now_[u];
    if (ak < 0 || ak == ai || u == best || world.is_immovable(ak)) continue;
    if (needs_swap(here, best, *rows_[ak], *rows_[ai]) && can_swap(best, here)) return ak;
  }
  return -1;
}

}  // namespace gdrhcr
