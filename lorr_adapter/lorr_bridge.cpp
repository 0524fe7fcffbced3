// The core side of the Start-Kit adapter: builds the grid, the distance table and the planner
// once, then turns every Start-Kit step into a planner step in the rotation model: its mapf steps
// with turns and waits (MapfInRotation) or its native rotation planning (GDRHCR_TURNS).
#include "lorr_bridge.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/map_prep.hpp"
#include "gdrhcr/mapf_in_rotation.hpp"
#include "gdrhcr/params.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr_lorr {

using namespace gdrhcr;
using Clock = std::chrono::steady_clock;

namespace {

std::string env_or(const char* name, const std::string& fallback) {
  const char* v = std::getenv(name);
  return v && *v ? std::string(v) : fallback;
}

double env_number(const char* name, double fallback) {
  const std::string s = env_or(name, "");
  if (s.empty()) return fallback;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (end == s.c_str() || *end != '\0' || !(v >= 0))
    throw std::invalid_argument(std::string(name) + " must be a non-negative number, not '" + s + "'");
  return v;
}

// "--H 10 --V=3" as (name, value) pairs.
std::vector<std::pair<std::string, std::string>> parse_params(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> words;
  for (std::string w; in >> w;) words.push_back(w);
  std::vector<std::pair<std::string, std::string>> out;
  for (size_t i = 0; i < words.size(); ++i) {
    const std::string& w = words[i];
    if (w.rfind("--", 0) != 0 || w.size() < 3)
      throw std::invalid_argument("GDRHCR_PARAMS: expected --NAME VALUE, got '" + w + "'");
    const auto eq = w.find('=');
    if (eq != std::string::npos) {
      out.emplace_back(w.substr(2, eq - 2), w.substr(eq + 1));
    } else {
      if (i + 1 >= words.size()) throw std::invalid_argument("GDRHCR_PARAMS: " + w + " needs a value");
      out.emplace_back(w.substr(2), words[++i]);
    }
  }
  return out;
}

Grid grid_of(int rows, int cols, const std::vector<int>& map) {
  if (rows <= 0 || cols <= 0 || map.size() != size_t(rows) * cols)
    throw std::invalid_argument("lorr adapter: the Start-Kit's map is not rows x cols");
  std::vector<std::string> lines(rows, std::string(cols, '.'));
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      if (map[size_t(r) * cols + c] == 1) lines[r][c] = '@';
  return Grid::from_rows(lines, "lorr-start-kit");
}

constexpr double kPlannerShare = 0.93;  // of our budget, for GD-RHCR's step-budget (and in trials)

// The Start-Kit's `enum Action {FW, CR, CCR, W, NA}` values.
constexpr int kStartKitWait = 3;
int start_kit_action(Action a) {
  switch (a) {
    case Action::kForward: return 0;
    case Action::kClockwise: return 1;
    case Action::kCounterClockwise: return 2;
    case Action::kWait: return kStartKitWait;
  }
  return kStartKitWait;
}

}  // namespace

void OverrunMemory::add(double overrun_s) {
  if (last_.size() < static_cast<size_t>(kWindow)) last_.push_back(overrun_s);
  else last_[next_] = overrun_s;
  next_ = (next_ + 1) % kWindow;
  double first = 0, second = 0;  // the two largest (none below 0)
  for (double o : last_) {
    if (o > first) second = first, first = o;
    else if (o > second) second = o;
  }
  planned_ = second;
}

int default_dist_budget_mb(uint64_t available_mb) {
  if (available_mb == 0) return kDistBudgetMb;
  return static_cast<int>(std::clamp<uint64_t>(available_mb * 3 / 4, 1, kDistBudgetMb));
}

uint64_t available_memory_mb() {
  std::ifstream in("/proc/meminfo");
  for (std::string key; in >> key;) {
    uint64_t kb = 0;
    if (key == "MemAvailable:" && in >> kb) return kb >> 10;
    in.ignore(std::numeric_limits<std::streamsize>::max(), '\n');
  }
  return 0;
}

BridgeOptions bridge_options_from_env() {
  BridgeOptions o;
  o.planner = env_or("GDRHCR_PLANNER", o.planner);
  o.params = parse_params(env_or("GDRHCR_PARAMS", ""));
  o.budget_ms = env_number("GDRHCR_BUDGET_MS", 0);
  o.times_out = env_or("GDRHCR_TIMES_OUT", "");
  o.seed = static_cast<uint64_t>(env_number("GDRHCR_SEED", 0));
  const double dist_mb = env_number("GDRHCR_DIST_MB", -1);
  o.dist_budget_mb = dist_mb < 0 ? default_dist_budget_mb(available_memory_mb()) : static_cast<int>(dist_mb);
  o.prep_dir = env_or("GDRHCR_PREP_DIR", "");
  if (o.dist_budget_mb < 1) throw std::invalid_argument("GDRHCR_DIST_MB must be at least 1");
  try {
    o.turns = env_or("GDRHCR_TURNS", "");
    if (!o.turns.empty()) parse_turn_planning(o.turns);  // a bad value is named now
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("GDRHCR_TURNS: ") + e.what());
  }
  return o;
}

struct Bridge::Impl {
  Impl(int rows, int cols, const std::vector<int>& map, int n, const BridgeOptions& o, Clock::time_point started)
      : options(o), grid(grid_of(rows, cols, map)), values(resolved_params(o, grid, n)),
        dist(grid, ActionModel::kRotation, size_t(o.dist_budget_mb) << 20,
             gdrhcr::step_costs(values, ActionModel::kRotation)),
        num_agents(n) {
    const TurnPlanning turns = o.turns.empty() ? kLorrTurnPlanning : parse_turn_planning(o.turns);
    if (turns == TurnPlanning::kMapfWait) {
      auto wrapped = std::make_unique<MapfInRotation>(make_planner(values, grid, n, o.seed), grid,
                                                      size_t(o.dist_budget_mb) << 20);
      planning_dist = &wrapped->mapf_dist();
      planner = std::move(wrapped);
    } else {
      planner = make_planner(values, grid, n, o.seed, ActionModel::kRotation);
      planning_dist = &dist;
    }
    std::fprintf(stderr, "gdrhcr lorr adapter: planner %s, turns %s, budget %g ms, threads %d, distance rows %d MB\n",
                 o.planner.c_str(), turn_planning_name(turns), o.budget_ms,
                 o.planner == "gd-rhcr" ? values.integer("threads") : 1, o.dist_budget_mb);
    if (!o.times_out.empty() && !(times = std::fopen(o.times_out.c_str(), "w")))
      throw std::invalid_argument("GDRHCR_TIMES_OUT: cannot write " + o.times_out);
    precompute_rows(o.preprocess_s > 0 ? started + std::chrono::duration_cast<Clock::duration>(
                                                     std::chrono::duration<double>(kRowsShare * o.preprocess_s))
                                       : Clock::time_point::max());
    pos.resize(n);
    headings.resize(n);
    next_headings.resize(n);
    next.resize(n);
    goals.resize(n);
    last_goal.assign(n, kNoCell);
  }

  // In the preprocessing phase: the row of every free cell, when all of them fit in the table's
  // memory budget (GDRHCR_DIST_MB), computed in batches on the thread pool until `deadline`.
  // Goals are not known before the first step (the Start-Kit reveals them then), but every goal
  // is a free cell: with every row at hand the first step plans at once, with no all-wait
  // warm-up, and no step spends its budget on the rows of new goals. When they do not all fit
  // (or the deadline comes first), rows are computed as goals come, as below.
  void precompute_rows(Clock::time_point deadline) {
    const auto t0 = Clock::now();
    const auto all = planning_dist->prefetch_all(deadline);
    const size_t cells = grid.free_cells().size(), mb = (all.bytes >> 20) + 1;
    if (!all.fit) {
      std::fprintf(stderr,
                   "gdrhcr lorr adapter: the rows of all %zu free cells need %zu MB, more than GDRHCR_DIST_MB %zu: "
                   "rows are computed as goals come\n",
                   cells, mb, planning_dist->budget_bytes() >> 20);
      return;
    }
    stats.rows_precomputed = all.computed;
    every_row = planning_dist->cached_rows() >= cells;
    std::fprintf(stderr, "gdrhcr lorr adapter: %zu of %zu rows computed before the first step (%zu MB) in %.1f s\n",
                 all.computed, cells, mb, std::chrono::duration<double>(Clock::now() - t0).count());
  }

  // The distance rows of the agents' goals (current ones first, then those revealed ahead),
  // computed until `deadline`. A row costs a search over the map, and the first step of a fleet
  // of thousands needs thousands of them. The table holds the rows it has not evicted (has()): a
  // goal that comes back after its row was evicted gets the row here again, not in the planner's
  // step, which would have to compute it past its budget.
  // Rows are computed in batches of kRowBatch on the thread pool (DistTable::prefetch).
  void warm_rows(Clock::time_point deadline) {
    if (rows_at_hand()) return;
    std::vector<Cell> batch;
    bool some = false;  // a batch was computed in this call
    auto flush = [&] {
      const auto t = Clock::now();
      planning_dist->prefetch(batch);
      if (!batch.empty()) batch_s = std::max(kBatchDecay * batch_s, std::chrono::duration<double>(Clock::now() - t).count());
      some = some || !batch.empty();
      batch.clear();
    };
    // A batch is started only when one like the slowest lately ends by the deadline, except the
    // first of the call: however short the budget, rows keep coming.
    const auto batch_time = [&] { return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(batch_s)); };
    for (int ahead = 0; ahead < 2; ++ahead)
      for (auto& g : goals)
        for (size_t k = ahead ? 1 : 0; k < (ahead ? g.size() : std::min<size_t>(1, g.size())); ++k) {
          if (planning_dist->has(g[k]) || std::find(batch.begin(), batch.end(), g[k]) != batch.end()) continue;
          if (some && Clock::now() + batch_time() > deadline) return flush();
          batch.push_back(g[k]);
          if (static_cast<int>(batch.size()) == kRowBatch) flush();
        }
    flush();
  }
  // The goals the planner gets: each agent's goals up to the first without a row; an agent whose
  // current goal has none yet keeps the goal it had (it waits there a step or two: the row comes
  // in a later step). False when some agent has no goal with a row at all (the first steps).
  bool goals_with_rows() {
    if (rows_at_hand()) {
      for (size_t i = 0; i < goals.size(); ++i) last_goal[i] = goals[i][0];
      return true;
    }
    for (size_t i = 0; i < goals.size(); ++i) {
      size_t k = 0;
      while (k < goals[i].size() && planning_dist->has(goals[i][k])) ++k;
      goals[i].resize(k);
      if (k == 0 && last_goal[i] == kNoCell) return false;
      if (k == 0) goals[i].push_back(last_goal[i]);
      last_goal[i] = goals[i][0];
    }
    return true;
  }

  // Every free cell's row computed beforehand and none evicted since: no goal needs a look-up
  // (with 10,000 agents three look-ups each took a millisecond or two of every step).
  bool rows_at_hand() const { return every_row && planning_dist->evictions() == 0; }

  ~Impl() {
    if (times) std::fclose(times);
  }
  // Our time for one step, to GDRHCR_TIMES_OUT, flushed at once (the Start-Kit ends with _exit).
  // Counts the step, and one over the budget.
  void record(Clock::time_point t0) {
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    ++stats.steps;
    if (options.budget_ms > 0 && ms > options.budget_ms) ++stats.over_budget;
    if (!times) return;
    std::fprintf(times, "%.3f\n", ms);
    std::fflush(times);
  }

  // The planner's parameters: GDRHCR_PARAMS and, unless they set them, what the adapter gives the
  // planner (GD-RHCR's step budget, its share of the cap, and the machine's cores for its pool and
  // the windowed LNS's zones; RHCR's timeout), resolved once. The planner and the world's rows both
  // use them, so that a rule that reads the budget (the open cost) is the same in both.
  static PlannerParams resolved_params(const BridgeOptions& o, const Grid& grid, int n) {
    Params params;
    for (auto& [k, v] : o.params) params.set(k, v);
    const double budget_s = o.budget_ms / 1000.0;
    if (budget_s > 0 && o.planner == "gd-rhcr" && !params.has("step-budget"))
      params.set("step-budget", std::to_string(kPlannerShare * budget_s));
    if (budget_s > 0 && o.planner == "rhcr" && !params.has("timeout")) params.set("timeout", std::to_string(budget_s));
    if (o.planner == "gd-rhcr" && !params.has("threads"))
      params.set("threads", std::to_string(std::max(1u, std::thread::hardware_concurrency())));
    PlannerParams values = PlannerParams::resolve(o.planner, params, MapFacts(grid, n, ActionModel::kRotation));
    params.check_all_used("GDRHCR_PARAMS for planner " + o.planner);
    return values;
  }

  static constexpr int kRowBatch = 2;  // rows computed at once: one row's time on two cores
  static constexpr double kRowsShare = 0.8;  // of the preprocessing limit, until the rows stop
  OverrunMemory overrun;  // how far the planner's steps ran past their budget lately
  static constexpr double kBatchDecay = 0.99;  // per batch, of batch_s
  double batch_s = 0;     // the slowest batch of rows lately
  BridgeStats stats;
  BridgeOptions options;
  std::FILE* times = nullptr;
  Grid grid;
  PlannerParams values;  // resolved_params: the planner's, and the world's rows' step costs
  DistTable dist;  // rotation rows: the world's, and the native planners'
  const DistTable* planning_dist = nullptr;  // the rows the planner uses
  int num_agents;
  std::unique_ptr<Planner> planner;
  std::vector<Cell> pos, next;
  std::vector<Heading> headings, next_headings;
  std::vector<std::vector<Cell>> goals;
  std::vector<Cell> last_goal;     // per agent: the goal it was last planned with
  bool every_row = false;          // precompute_rows computed the row of every free cell
};

namespace {

constexpr double kPrepMaxSeconds = 600;

// The offline preparation for this map and fleet (GDRHCR_PREP_DIR): loaded from its cache file,
// or made within a third of the preprocessing limit (at most 10 minutes) and cached. Its traffic
// cost joins the planner's parameters unless they set one. A file that cannot be written is
// reported and the preparation is used all the same.
BridgeOptions with_prep(BridgeOptions o, const Grid& grid, int n) {
  if (o.prep_dir.empty() || !planner_has_param(o.planner, "traffic-cost")) return o;
  for (auto& [k, v] : o.params)
    if (Params::canonical(k) == "traffic-cost") return o;
  const std::string path = o.prep_dir + "/" + prep_file_name(grid, n, ActionModel::kRotation);
  MapPrep prep;
  try {
    prep = load_prep(path, grid, n, ActionModel::kRotation);
    std::fprintf(stderr, "gdrhcr lorr adapter: preparation loaded from %s\n", path.c_str());
  } catch (const PrepError& e) {
    if (std::ifstream(path).good())
      std::fprintf(stderr, "gdrhcr lorr adapter: %s; preparing again\n", e.what());
    else
      std::fprintf(stderr, "gdrhcr lorr adapter: no preparation file %s yet; preparing\n", path.c_str());
    PrepOptions po;
    po.agents = n;
    po.planner = o.planner;
    for (auto& [k, v] : o.params) po.given.set(k, v);
    po.seed = o.seed;
    po.dist_budget_mb = o.dist_budget_mb;
    if (o.budget_ms > 0 && planner_has_param(o.planner, "step-budget"))  // trials at the run's budget
      po.step_budget_s = kPlannerShare * o.budget_ms / 1000;
    po.time_limit_s = o.preprocess_s > 0 ? std::min(o.preprocess_s / 3, kPrepMaxSeconds) : kPrepMaxSeconds;
    prep = prepare_map(grid, po);
    try {
      save_prep(prep, path);
    } catch (const PrepError& w) {
      std::fprintf(stderr, "gdrhcr lorr adapter: %s (the preparation is used, not cached)\n", w.what());
    }
  }
  std::fprintf(stderr, "gdrhcr lorr adapter: traffic-cost %g from the preparation\n", prep.traffic_cost);
  o.params.emplace_back("traffic-cost", std::to_string(prep.traffic_cost));
  return o;
}

}  // namespace

Bridge::Bridge(int rows, int cols, const std::vector<int>& map, int num_agents, const BridgeOptions& options) {
  const auto started = Clock::now();  // the preprocessing phase's limit counts from here
  impl_ = std::make_unique<Impl>(rows, cols, map, num_agents, with_prep(options, grid_of(rows, cols, map), num_agents),
                                 started);
}

Bridge::~Bridge() = default;

StepCosts Bridge::step_costs() const { return impl_->dist.step_costs(); }

BridgeStats Bridge::stats() const {
  BridgeStats s = impl_->stats;
  s.evictions = impl_->planning_dist->evictions();
  return s;
}

void Bridge::plan(int timestep, double time_limit_s, const std::vector<int>& locations,
                  const std::vector<int>& headings, const std::vector<std::vector<int>>& goal_locations,
                  std::vector<int>& actions) {
  const auto t0 = Clock::now();
  Impl& m = *impl_;
  const int n = m.num_agents;
  if (static_cast<int>(locations.size()) != n || static_cast<int>(headings.size()) != n)
    throw std::invalid_argument("lorr adapter: the Start-Kit gave " + std::to_string(locations.size()) +
                                " agents, expected " + std::to_string(n));
  for (int i = 0; i < n; ++i) {
    m.pos[i] = locations[i];
    m.goals[i].clear();
    const auto& g = i < static_cast<int>(goal_locations.size()) ? goal_locations[i] : std::vector<int>{};
    for (int c : g) m.goals[i].push_back(c);
    if (m.goals[i].empty()) m.goals[i].push_back(m.pos[i]);  // no task: stay put
    m.headings[i] = static_cast<Heading>(headings[i]);
  }
  actions.assign(n, kStartKitWait);
  // Rows first (none to compute when every cell's row was computed beforehand), within half our
  // budget (30% of the Start-Kit's limit without one; a batch of rows is begun only if one like
  // the slowest lately would end in time); agents whose goal rows are not ready keep their last
  // goal; the planner gets what is left of kPlannerShare of the budget. While some agent has had
  // no goal with a row yet (the first steps of a fleet of thousands: 10,000 rows take seconds),
  // the step is all waits (valid) and rows get 90% of our budget (30% of the Start-Kit's limit
  // without one): the warm-up is paid once, in the first steps, and with a budget it keeps the
  // budget too; the step that completes it is still all waits, as the rows leave the planner no
  // time (a first step that computed no row plans).
  const auto limit = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(time_limit_s));
  const auto budget = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double, std::milli>(m.options.budget_ms));
  const bool capped = m.options.budget_ms > 0 && budget < limit;
  const bool warming = std::find(m.last_goal.begin(), m.last_goal.end(), kNoCell) != m.last_goal.end();
  const uint64_t rows_at_start = m.planning_dist->bfs_count();
  m.warm_rows(t0 + (!capped ? limit * 3 / 10 : warming ? budget * 9 / 10 : budget / 2));
  const uint64_t rows_now = m.planning_dist->bfs_count() - rows_at_start;
  m.stats.rows_before_planning += rows_now;
  if (!m.goals_with_rows() || (warming && capped && rows_now > 0)) {
    ++m.stats.warm_up_steps;
    std::fprintf(stderr, "gdrhcr lorr adapter: timestep %d: computing distance rows, every agent waits\n", timestep);
    m.record(t0);
    return;
  }
  std::fill(m.next.begin(), m.next.end(), kNoCell);
  WorldView view{m.grid, m.dist, timestep, m.pos, m.goals};
  view.action_model = ActionModel::kRotation;
  view.headings = &m.headings;
  view.next_headings = &m.next_headings;
  // The planner's share less the rows' time and less what its steps ran past the budget they
  // were given lately (the work after its deadlines: with 3,000 agents 5-10 ms), at least a tenth.
  // The share less the rows' time is also the step's hard limit: where PIBT alone takes nearly
  // the whole budget (10,000 agents at 10 ms), it stops there rather than run past the cap.
  const auto t_plan = Clock::now();
  if (capped) {
    const double used = std::chrono::duration<double>(t_plan - t0).count();
    const double share = kPlannerShare * m.options.budget_ms / 1000.0;
    view.step_budget_s = std::max(share / 10, share - used - m.overrun.planned_s());
    view.step_limit_s = std::max(share / 10, share - used);
  }
  const uint64_t rows_before = m.planning_dist->bfs_count();
  m.planner->plan_step(view, m.next);
  const uint64_t planner_rows = m.planning_dist->bfs_count() - rows_before;
  m.stats.rows_in_planner += planner_rows;
  // The planner's counters so far, every kStatsEvery steps (the Start-Kit ends with _exit, so
  // there is no summary at the end): how many steps planned over operations, what the search did.
  if ((timestep + 1) % kStatsEvery == 0)
    std::fprintf(stderr, "gdrhcr lorr adapter: timestep %d: planner stats %s\n", timestep,
                 m.planner->stats().dump().c_str());
  if (capped) {
    const double ran = std::chrono::duration<double>(Clock::now() - t_plan).count();
    m.overrun.add(ran - view.step_budget_s);
    const double took_ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    if (took_ms > m.options.budget_ms)
      std::fprintf(stderr,
                   "gdrhcr lorr adapter: timestep %d took %.1f ms of a %g ms budget: rows and input %.1f ms, planner %.1f ms "
                   "of %.1f given, %llu rows computed in the planner\n",
                   timestep, took_ms, m.options.budget_ms, took_ms - 1000 * ran, 1000 * ran,
                   1000 * view.step_budget_s, static_cast<unsigned long long>(planner_rows));
  }
  for (int i = 0; i < n; ++i) {
    const auto a = action_between(m.grid, Pose{m.pos[i], m.headings[i]}, Pose{m.next[i], m.next_headings[i]});
    if (!a) throw std::logic_error("lorr adapter: the planner's step for agent " + std::to_string(i) + " is no action");
    actions[i] = start_kit_action(*a);
  }
  m.record(t0);
}

}  // namespace gdrhcr_lorr
