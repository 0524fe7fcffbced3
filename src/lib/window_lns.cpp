// See window_lns.hpp (issue 24; WPPL, arXiv 2404.16162; MAPF-LNS, IJCAI 2021).
#include "gdrhcr/window_lns.hpp"

#include <algorithm>
#include <chrono>
#include <climits>
#include <numeric>
#include <stdexcept>
#include <system_error>
#include <thread>

#include "gdrhcr/open_list.hpp"

namespace gdrhcr {

namespace {
constexpr int kNeighbourRadius = 4;  // agents this many steps from the picked one join it
constexpr float kTurnTieBreak = 1e-3f;
// The search ends early once this many rounds over the delayed agents (at least kStaleMin
// neighbourhoods) in a row lowered nothing: the plan is as good as it gets, and the rest of the
// budget is left to the machine.
constexpr long kStaleRounds = 4;
constexpr long kStaleMin = 100;
constexpr int kMaxGrowth = 4;  // a stalled search doubles its neighbourhoods up to this many times the size
constexpr float kKeepTieBreak = 1e-2f;
constexpr float kFreeMove = 1e-3f;  // a move or turn after the goal
constexpr size_t kZonedHeld = 2;     // the zones must hold at least 1/kZonedHeld of the delayed agents
// A neighbourhood is planned up to this many times, each time with the agent that found no path
// first: failed neighbourhoods feed a jam (docs/results.md, session 29).
constexpr int kAttempts = 4;
// The running estimates of the planner beneath's time and a rollout step's: the newest measure's
// weight, and their decay per step without a search.
constexpr double kEstimateWeight = 0.25;
constexpr double kEstimateDecay = 0.995;
void blend(double& estimate, double measure) {
  estimate = estimate > 0 ? (1 - kEstimateWeight) * estimate + kEstimateWeight * measure : measure;
}
}  // namespace

// One space-time A*'s scratch: per state (t, reached, cell, heading) a stamp and a parent, reset in
// O(1) by bumping the stamp.
struct WindowLns::Search {
  std::vector<uint32_t> seen, closed;
  std::vector<int32_t> parent;
  std::vector<float> g;
  uint32_t stamp = 0;
  OpenList open;
  void begin(size_t states) {
    if (seen.size() < states)
      seen.assign(states, 0), closed.assign(states, 0), parent.assign(states, -1), g.assign(states, 0), stamp = 0;
    if (++stamp == 0) {
      std::fill(seen.begin(), seen.end(), 0);
      std::fill(closed.begin(), closed.end(), 0);
      stamp = 1;
    }
    open.clear();
  }
};

struct WindowLns::Worker {
  explicit Worker(uint64_t seed) : rng(seed) {}
  // Its zone: the agents whose start's coordinate along `axis` (0 x, 1 y) lies in [lo, hi].
  bool holds(const Grid& grid, Cell c) const {
    const int v = axis ? grid.y_of(c) : grid.x_of(c);
    return v >= lo && v <= hi;
  }
  std::mt19937_64 rng;
  Search search;
  int size = 0;  // agents per neighbourhood in this step's search
  int axis = 0, lo = INT_MIN, hi = INT_MAX;
  std::vector<int> delayed;  // the delayed agents of its zone
  long tried = 0, kept = 0, gained = 0, failed = 0;
};

WindowLns::WindowLns(std::unique_ptr<Planner> inner, const Grid& grid, int num_agents, WindowLnsConfig config,
                     PibtOptions rollout, ActionModel model)
    : inner_(std::move(inner)),
      grid_(grid),
      cfg_(config),
      pibt_(grid, num_agents, config.seed ^ 0x5eedULL, rollout),
      cells_(grid.num_cells()) {
  if (cfg_.window < 1) throw std::invalid_argument("window LNS: the window must be at least one step");
  if (cfg_.neighbourhood < 1) throw std::invalid_argument("window LNS: a neighbourhood needs at least one agent");
  if (cfg_.threads < 1) throw std::invalid_argument("window LNS: threads must be at least 1");
  for (int k = 0; k < cfg_.threads; ++k) {
    workers_.push_back(std::make_unique<Worker>(cfg_.seed + 0x9e3779b97f4a7c15ULL * static_cast<uint64_t>(k)));
    workers_.back()->search.begin(states(model));  // now, not in the first step's budget
  }
}

// The A*'s states: (t, reached, cell, heading), the cells those of the box of side 2 x window + 1
// around the agent's start (it cannot leave the box in the window), whatever the map's size.
size_t WindowLns::states(ActionModel model) const {
  const size_t k = model == ActionModel::kRotation ? kNumHeadings : 1;
  const size_t side = 2 * static_cast<size_t>(cfg_.window) + 1;
  return 2 * side * side * k * (cfg_.window + 1);
}

WindowLns::~WindowLns() = default;

nlohmann::json WindowLns::params() const {
  nlohmann::json j = inner_->params();
  j["lns_window"] = cfg_.window;
  j["lns_neighbourhood"] = cfg_.neighbourhood;
  j["lns_iterations"] = cfg_.iterations;
  return j;
}

nlohmann::json WindowLns::stats() const {
  nlohmann::json j = inner_->stats();
  j["lns_steps"] = steps_searched_;
  j["lns_steps_cut"] = rollouts_cut_;
  j["lns_steps_skipped"] = rollouts_skipped_;
  j["lns_rollout_step_ms"] = 1000 * rollout_step_s_;
  j["lns_steps_ended_stale"] = stale_stops_;
  long tried = 0, kept = 0, gained = 0, failed = 0;
  for (const auto& w : workers_) tried += w->tried, kept += w->kept, gained += w->gained, failed += w->failed;
  j["lns_steps_zoned"] = zoned_steps_;
  j["lns_neighbourhoods"] = tried;
  j["lns_kept"] = kept;
  j["lns_cost_gained"] = gained;
  j["lns_failed_searches"] = failed;
  j["lns_time_s"] = search_s_;
  return j;
}

std::vector<Cell> WindowLns::planned_path(int agent) const {
  if (paths_.empty()) return inner_->planned_path(agent);
  std::vector<Cell> cells;
  for (const Pose& p : paths_[agent]) cells.push_back(p.cell);
  return cells;
}

Cell WindowLns::intended_next(int agent, Cell at) const {
  if (paths_.empty()) return inner_->intended_next(agent, at);
  return cell_after_step(planned_path(agent), at);
}

long WindowLns::plan_cost() const { return std::accumulate(cost_.begin(), cost_.end(), 0L); }

// What the distance rows charge for the step from a to b: a forward move what the step costs say
// (lanes, traffic), a turn or a wait 1.
int WindowLns::step_cost(const WorldView& world, Pose a, Pose b) {
  return a.cell != b.cell && world.rotation() ? world.dist.forward_cost(b.cell, b.heading) : 1;
}

// The steps' costs until the agent first stands on its goal, else until the window's end plus the
// distance from its last pose.
long WindowLns::cost_of(const WorldView& world, int agent, const std::vector<Pose>& path) const {
  const DistRow& row = *rows_[agent];
  long cost = 0;
  for (int t = 0; t < cfg_.window; ++t) {
    if (path[t].cell == row.goal()) return cost;
    cost += step_cost(world, path[t], path[t + 1]);
  }
  if (path[cfg_.window].cell == row.goal()) return cost;
  return cost + row.at(path[cfg_.window].cell, world.rotation() ? path[cfg_.window].heading : kEast);
}

void WindowLns::reserve(int agent, const std::vector<Pose>& path, bool on) {
  for (int t = 0; t <= cfg_.window; ++t) at(t, path[t].cell) = on ? agent : -1;
}

// PIBT carries the planner's first step on to the window's end; an agent that reaches its goal on
// the way sets out for its next known one.
bool WindowLns::rollout(const WorldView& world, const std::vector<Cell>& next, Clock::time_point stop) {
  const int n = world.num_agents();
  const bool rot = world.rotation();
  paths_.assign(n, std::vector<Pose>(cfg_.window + 1));
  std::vector<std::vector<Cell>> goals(n);
  std::vector<size_t> goal_index(n, 0);
  for (int i = 0; i < n; ++i) {
    paths_[i][0] = world.pose(i);
    paths_[i][1] = {next[i], rot ? (*world.next_headings)[i] : kEast};
    goals[i] = {world.goals[i][0]};
  }
  auto advance_goal = [&](int i, Cell at) {
    if (at != goals[i][0]) return;
    if (goal_index[i] + 1 < world.goals[i].size()) goals[i][0] = world.goals[i][++goal_index[i]];
  };
  for (int i = 0; i < n; ++i) advance_goal(i, next[i]);
  std::vector<Cell> pos(n), nxt(n);
  std::vector<Heading> heads(n), next_heads(n);
  const auto t0 = Clock::now();
  for (int t = 1; t < cfg_.window; ++t) {
    for (int i = 0; i < n; ++i) pos[i] = paths_[i][t].cell, heads[i] = paths_[i][t].heading;
    WorldView view{world.grid, world.dist, world.timestep + t, pos, goals};
    view.action_model = world.action_model;
    if (rot) view.headings = &heads, view.next_headings = &next_heads;
    pibt_.step(view, nxt);
    for (int i = 0; i < n; ++i) {
      paths_[i][t + 1] = {nxt[i], rot ? next_heads[i] : kEast};
      advance_goal(i, nxt[i]);
    }
    const auto now = Clock::now();
    if (now >= stop || t + 1 == cfg_.window)  // this rollout's time per step, into the estimate
      blend(rollout_step_s_, std::chrono::duration<double>(now - t0).count() / t);
    if (now >= stop) return false;
  }
  return true;
}

// Space-time A* for `agent` around everyone's reservations (its own taken out), minimising cost_of.
// A state is (t, reached, cell, heading): once the agent has stood on its goal its steps cost
// nothing (a move kFreeMove, so it stays unless it is in the way), as it gets its next errand
// there. False when no path is found within kMaxExpansions.
bool WindowLns::replan(const WorldView& world, int agent, std::vector<Pose>& path, Search& s) {
  const DistRow& row = *rows_[agent];
  const Cell goal = row.goal();
  const int W = cfg_.window;
  const int K = world.rotation() ? kNumHeadings : 1;
  const Pose start = path[0];
  // A state's cell is numbered in the box of side 2W + 1 around the start: the agent cannot leave it.
  const int side = 2 * W + 1, x0 = grid_.x_of(start.cell) - W, y0 = grid_.y_of(start.cell) - W;
  const size_t layer = static_cast<size_t>(side) * side * K;
  s.begin(states(world.action_model));
  auto id_of = [&](int t, int r, Cell c, Heading h) {
    const size_t local = static_cast<size_t>(grid_.y_of(c) - y0) * side + (grid_.x_of(c) - x0);
    return static_cast<int32_t>((2 * t + r) * layer + local * K + (K > 1 ? h : 0));
  };
  auto pose_of = [&](int32_t id) -> Pose {
    const size_t local = (id % layer) / K;
    return {grid_.cell(x0 + static_cast<int>(local % side), y0 + static_cast<int>(local / side)),
            static_cast<Heading>(K > 1 ? id % K : kEast)};
  };
  auto h_of = [&](Cell c, Heading h) { return K > 1 ? row.at(c, h) : row[c]; };
  // Among equally cheap paths, the one the last step planned (carried one step on).
  const bool keep = static_cast<int>(last_.size()) > agent && last_[agent][1] == start;
  const int r0 = start.cell == goal ? 1 : 0;
  const int32_t id0 = id_of(0, r0, start.cell, start.heading);
  s.seen[id0] = s.stamp, s.parent[id0] = -1, s.g[id0] = 0;
  s.open.push(r0 ? 0.0f : static_cast<float>(h_of(start.cell, start.heading)), 0, id0);
  int expansions = 0;
  int32_t found = -1;
  while (!s.open.empty() && expansions < WindowLnsConfig::kMaxExpansions) {
    const int32_t id = s.open.pop();
    if (s.closed[id] == s.stamp) continue;
    s.closed[id] = s.stamp;
    ++expansions;
    const int t = static_cast<int>(id / (2 * layer));
    const int r = static_cast<int>(id / layer) & 1;
    const auto [c, hd] = pose_of(id);
    if (t == W) {
      found = id;
      break;
    }
    auto visit = [&](Cell c2, Heading h2) {
      if (at(t + 1, c2) >= 0) return;
      if (c2 != c) {  // a swap with the agent coming the other way
        const int b = at(t, c2);
        if (b >= 0 && at(t + 1, c) == b) return;
      }
      const int r2 = r || c2 == goal;
      const int d = r2 ? 0 : h_of(c2, h2);
      if (d >= kUnreachable) return;
      const int32_t id2 = id_of(t + 1, r2, c2, h2);
      // Before the goal a step costs what the rows charge for it, a turn kTurnTieBreak more (so a
      // wait beats a turn and its undoing); after it, only a move or turn, kFreeMove.
      const bool still = c2 == c && h2 == hd;
      float g2 = s.g[id] + (r ? (still ? 0.0f : kFreeMove)
                              : static_cast<float>(step_cost(world, {c, hd}, {c2, h2})) +
                                    (c2 == c && h2 != hd ? kTurnTieBreak : 0.0f));
      if (keep && t + 2 <= W && last_[agent][t + 2] != Pose{c2, K > 1 ? h2 : kEast}) g2 += kKeepTieBreak;
      if (s.seen[id2] == s.stamp && s.g[id2] <= g2) return;
      s.seen[id2] = s.stamp, s.parent[id2] = id, s.g[id2] = g2;
      s.open.push(g2 + static_cast<float>(d), t + 1, id2);
    };
    if (K > 1) {
      for (Action a : {Action::kForward, Action::kClockwise, Action::kCounterClockwise, Action::kWait}) {
        const Pose p = apply_action(grid_, {c, hd}, a);
        if (p.cell != kNoCell) visit(p.cell, p.heading);
      }
    } else {
      visit(c, kEast);
      for (Cell c2 : grid_.neighbours(c)) visit(c2, kEast);
    }
  }
  if (found < 0) return false;
  int t = W;
  for (int32_t id = found; id >= 0; id = s.parent[id], --t) path[t] = pose_of(id);
  return true;
}

// The agents in the way of the picked one: along the path it would take alone (down its distance,
// one action a step), those planned in each of its cells at that step or the next, in path order.
void WindowLns::add_blockers(const WorldView& world, int seed_agent, std::vector<int>& agents, const Worker& w) const {
  const DistRow& row = *rows_[seed_agent];
  const bool rot = world.rotation();
  Pose p = world.pose(seed_agent);
  auto add = [&](int b) {
    if (b >= 0 && static_cast<int>(agents.size()) < w.size && w.holds(grid_, world.positions[b]) &&
        std::find(agents.begin(), agents.end(), b) == agents.end())
      agents.push_back(b);
  };
  for (int t = 0; t < cfg_.window && p.cell != row.goal(); ++t) {
    Pose best = p;
    int best_d = rot ? row.at(p.cell, p.heading) : row[p.cell];
    if (rot) {
      for (Action a : {Action::kForward, Action::kClockwise, Action::kCounterClockwise}) {
        const Pose q = apply_action(grid_, p, a);
        if (q.cell != kNoCell && row.at(q.cell, q.heading) < best_d) best = q, best_d = row.at(q.cell, q.heading);
      }
    } else {
      for (Cell c2 : grid_.neighbours(p.cell))
        if (row[c2] < best_d) best = {c2, kEast}, best_d = row[c2];
    }
    if (best == p) break;
    p = best;
    add(at(t + 1, p.cell));
    if (t + 2 <= cfg_.window) add(at(t + 2, p.cell));
  }
}

// The picked agent, then (every other neighbourhood) the agents in its way, then the agents standing
// nearest it (breadth first, up to kNeighbourRadius steps).
std::vector<int> WindowLns::neighbourhood(const WorldView& world, int seed_agent, Worker& w) {
  std::vector<int> agents{seed_agent};
  if (w.rng() & 1) add_blockers(world, seed_agent, agents, w);
  std::vector<Cell> frontier{world.positions[seed_agent]}, next_frontier;
  std::vector<Cell> visited{world.positions[seed_agent]};
  for (int r = 0; r < kNeighbourRadius && static_cast<int>(agents.size()) < w.size; ++r) {
    next_frontier.clear();
    for (Cell c : frontier)
      for (Cell c2 : grid_.neighbours(c)) {
        if (std::find(visited.begin(), visited.end(), c2) != visited.end()) continue;
        visited.push_back(c2);
        next_frontier.push_back(c2);
      }
    std::shuffle(next_frontier.begin(), next_frontier.end(), w.rng);
    for (Cell c2 : next_frontier) {
      const int b = at(0, c2);
      if (b >= 0 && static_cast<int>(agents.size()) < w.size && w.holds(grid_, c2) &&
          std::find(agents.begin(), agents.end(), b) == agents.end())
        agents.push_back(b);
    }
    frontier.swap(next_frontier);
  }
  return agents;
}

// One neighbourhood: its paths planned again, and kept when they cost no more in sum. True when
// they cost less.
bool WindowLns::improve_once(const WorldView& world, Worker& w, Clock::time_point stop) {
  // The picked agent: of two delayed agents drawn at random, the one the plan delays more.
  int pick = -1;
  long delay = 0;
  for (int k = 0; k < 2; ++k) {
    const int a = w.delayed[w.rng() % w.delayed.size()];
    const long d = cost_[a] - lower_[a];
    if (pick < 0 || d > delay) pick = a, delay = d;
  }
  if (delay <= 0) return false;
  std::vector<int> agents = neighbourhood(world, pick, w);
  std::shuffle(agents.begin(), agents.end(), w.rng);
  ++w.tried;
  long before = 0, after = 0;
  std::vector<std::vector<Pose>> old;
  std::vector<long> fresh;
  for (int a : agents) before += cost_[a], old.push_back(paths_[a]), reserve(a, paths_[a], false);
  size_t done = 0;
  for (int attempt = 0; attempt < kAttempts; ++attempt) {  // the agent that found no path goes first
    for (done = 0, after = 0, fresh.clear(); done < agents.size(); ++done) {
      const int a = agents[done];
      if (Clock::now() >= stop || !replan(world, a, paths_[a], w.search)) break;  // the deadline: as a failure
      reserve(a, paths_[a], true);
      fresh.push_back(cost_of(world, a, paths_[a]));
      after += fresh.back();
    }
    if (done == agents.size() || done == 0 || Clock::now() >= stop) break;
    for (size_t k = 0; k < done; ++k) reserve(agents[k], paths_[agents[k]], false);
    std::rotate(agents.begin(), agents.begin() + done, agents.begin() + done + 1);
    std::rotate(old.begin(), old.begin() + done, old.begin() + done + 1);
  }
  if (done == agents.size() && after <= before) {  // an equal plan is kept too: the search drifts on
    for (size_t k = 0; k < agents.size(); ++k) cost_[agents[k]] = fresh[k];
    ++w.kept, w.gained += before - after;
    return after < before;
  }
  if (done < agents.size()) ++w.failed;
  for (size_t k = 0; k < done; ++k) reserve(agents[k], paths_[agents[k]], false);
  for (size_t k = 0; k < agents.size(); ++k) paths_[agents[k]] = old[k], reserve(agents[k], old[k], true);
  return false;
}

// Until `stop` or `iterations` (> 0), or (without them) until a run of neighbourhoods as long as
// kStaleRounds times the delayed agents (at least kStaleMin) has lowered nothing, after doubling
// the neighbourhoods' size up to kMaxGrowth times.
bool WindowLns::search(const WorldView& world, Worker& w, Clock::time_point stop, long iterations) {
  w.size = cfg_.neighbourhood;
  const long stale_limit = std::max<long>(kStaleMin, kStaleRounds * static_cast<long>(w.delayed.size()));
  long stale = 0;
  for (long k = 0; !w.delayed.empty() && (iterations <= 0 || k < iterations); ++k) {
    if (Clock::now() >= stop) break;
    stale = improve_once(world, w, stop) ? 0 : stale + 1;
    if (iterations <= 0 && stale >= stale_limit) {
      if (w.size < kMaxGrowth * cfg_.neighbourhood) {
        w.size *= 2;
        stale = 0;
        continue;
      }
      return false;
    }
  }
  return true;
}

int WindowLns::make_zones(const WorldView& world) {
  const int axis = grid_.height() > grid_.width() ? 1 : 0;
  std::vector<int> v;
  for (int a : delayed_) v.push_back(axis ? grid_.y_of(world.positions[a]) : grid_.x_of(world.positions[a]));
  std::sort(v.begin(), v.end());
  // A search reaches kNeighbourRadius cells (its neighbours) and `window` cells (paths) from its agents.
  const int margin = std::max(cfg_.window, kNeighbourRadius) + 1;
  for (int zones = static_cast<int>(workers_.size()); zones >= 2; --zones) {
    size_t held = 0;
    bool fits = static_cast<int>(v.size()) >= 2 * zones;
    for (int k = 0; fits && k < zones; ++k) {
      Worker& w = *workers_[k];
      w.axis = axis;
      w.lo = k == 0 ? INT_MIN : v[v.size() * k / zones] + margin;
      w.hi = k + 1 == zones ? INT_MAX : v[v.size() * (k + 1) / zones] - margin;
      w.delayed.clear();
      if (w.lo <= w.hi)
        for (int a : delayed_)
          if (w.holds(grid_, world.positions[a])) w.delayed.push_back(a);
      fits = !w.delayed.empty();
      held += w.delayed.size();
    }
    if (fits && held * kZonedHeld >= delayed_.size()) return zones;  // else the margins leave out too many
  }
  return 1;
}

// The zones at once, one thread each, for kZonedShare of the time to `stop` (and of `iterations`
// when > 0); returns the iterations left for the search over everyone.
long WindowLns::search_zones(const WorldView& world, int zones, Clock::time_point stop, long iterations) {
  ++zoned_steps_;
  auto zoned_stop = stop;
  if (stop != Clock::time_point::max())
    zoned_stop = Clock::now() + std::chrono::duration_cast<Clock::duration>((stop - Clock::now()) * WindowLnsConfig::kZonedShare);
  const long zoned = iterations > 0 ? std::max(1L, static_cast<long>(iterations * WindowLnsConfig::kZonedShare) / zones)
                                    : 0;
  std::vector<std::thread> threads;
  for (int k = 1; k < zones; ++k) {
    try {
      threads.emplace_back([&, k] { search(world, *workers_[k], zoned_stop, zoned); });
    } catch (const std::system_error&) {  // no thread to be had: this zone here, before the first
      search(world, *workers_[k], zoned_stop, zoned);
    }
  }
  search(world, *workers_[0], zoned_stop, zoned);
  for (auto& t : threads) t.join();
  return iterations > 0 ? std::max(0L, iterations - zoned * zones) : iterations;
}

StepReport WindowLns::plan_step(const WorldView& world, std::vector<Cell>& next) {
  const auto t0 = Clock::now();
  double budget = cfg_.step_budget_s;
  if (world.step_budget_s > 0) budget = budget > 0 ? std::min(budget, world.step_budget_s) : world.step_budget_s;
  // When the planner beneath (as it ran with its share lately) and a rollout of the whole window
  // would not end before the stop, the search is skipped and the planner beneath gets the budget up
  // to the stop (a rollout cut short is time lost; searches over shorter windows lost errands on
  // warehouse_large). A skipped step measures no rollout, so both estimates decay: now and then a
  // step tries again.
  const bool room = budget <= 0 || inner_s_ <= 0 || rollout_step_s_ <= 0 ||
                    inner_s_ + cfg_.window * rollout_step_s_ <= budget * WindowLnsConfig::kStopShare;
  WorldView view = world;
  if (budget > 0) view.step_budget_s = budget * (room ? WindowLnsConfig::kInnerShare : WindowLnsConfig::kStopShare);
  StepReport report = inner_->plan_step(view, next);
  const double inner_s = std::chrono::duration<double>(Clock::now() - t0).count();
  // Given the whole budget, a step that ended within the share tells the share's time too.
  if (room || inner_s <= budget * WindowLnsConfig::kInnerShare) blend(inner_s_, inner_s);
  paths_.clear();
  if (world.timestep != last_timestep_ + 1) last_.clear();
  const bool taken = (world.immovable && std::any_of(world.immovable->begin(), world.immovable->end(),
                                                     [](uint8_t x) { return x != 0; })) ||
                     (world.blocked && !world.blocked->empty());
  if (taken || (budget <= 0 && cfg_.iterations <= 0) || world.num_agents() == 0) return report;
  const auto stop = budget <= 0 ? Clock::time_point::max()
                                : t0 + std::chrono::duration_cast<Clock::duration>(
                                           std::chrono::duration<double>(budget * WindowLnsConfig::kStopShare));
  // The rollout of window - 1 steps, and one more step's time for the search, must fit before the stop.
  if (budget > 0 && rollout_step_s_ > 0 &&
      (!room || std::chrono::duration<double>(stop - Clock::now()).count() < cfg_.window * rollout_step_s_)) {
    ++rollouts_skipped_;
    inner_s_ *= kEstimateDecay, rollout_step_s_ *= kEstimateDecay;
    return report;
  }
  const auto s0 = Clock::now();
  const int n = world.num_agents();
  rows_.resize(n);
  for (int i = 0; i < n; ++i)
    if (!rows_[i] || rows_[i]->goal() != world.goals[i][0]) rows_[i] = world.dist.row(world.goals[i][0]);
  if (!rollout(world, next, stop)) {  // no time left to search: the step beneath stands
    paths_.clear();
    ++rollouts_cut_;
    search_s_ += std::chrono::duration<double>(Clock::now() - s0).count();
    return report;
  }
  reserved_.assign(static_cast<size_t>(cfg_.window + 1) * cells_, -1);
  cost_.assign(n, 0);
  lower_.assign(n, 0);
  delayed_.clear();
  for (int i = 0; i < n; ++i) {
    reserve(i, paths_[i], true);
    cost_[i] = cost_of(world, i, paths_[i]);
    lower_[i] = world.rotation() ? rows_[i]->at(world.positions[i], (*world.headings)[i]) : (*rows_[i])[world.positions[i]];
    if (cost_[i] > lower_[i]) delayed_.push_back(i);
  }
  ++steps_searched_;
  long iterations = cfg_.iterations;  // 0: until the deadline or a stale run
  const int zones = workers_.size() > 1 ? make_zones(world) : 1;
  if (zones > 1) iterations = search_zones(world, zones, stop, iterations);  // then everyone
  Worker& w = *workers_[0];
  w.axis = 0, w.lo = INT_MIN, w.hi = INT_MAX, w.delayed = delayed_;
  if ((cfg_.iterations <= 0 || iterations > 0) && !search(world, w, stop, iterations)) ++stale_stops_;
  for (int i = 0; i < n; ++i) {
    next[i] = paths_[i][1].cell;
    if (world.rotation()) (*world.next_headings)[i] = paths_[i][1].heading;
  }
  last_ = paths_;
  last_timestep_ = world.timestep;
  search_s_ += std::chrono::duration<double>(Clock::now() - s0).count();
  report.planned = true;
  report.plan_time_s = std::chrono::duration<double>(Clock::now() - t0).count();
  return report;
}

}  // namespace gdrhcr
