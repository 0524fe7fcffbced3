// Our planner behind the League of Robot Runners Start-Kit's MAPFPlanner (LoRR 2023, Start-Kit
// v1.1.5, MIT): the Start-Kit's side (MAPFPlanner.cpp) sees only this header, which uses standard
// types alone, so the Start-Kit's own nlohmann/json copy never meets the core's.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace gdrhcr {
struct StepCosts;
}

namespace gdrhcr_lorr {

// Read from the environment (scripts/bench_lorr.sh sets them):
//   GDRHCR_PLANNER    a name of gdrhcr::make_planner (default gd-rhcr)
//   GDRHCR_PARAMS     its parameters as on gdrhcr_sim's command line, e.g. "--H 10 --V 3";
//                     GD-RHCR's threads are the machine's cores unless it sets them
//   GDRHCR_BUDGET_MS  our time per step in ms (0 = none), distance rows included: unless every
//                     cell's row was computed beforehand (GDRHCR_DIST_MB), the rows of new
//                     goals get up to half of it (an agent whose goal has no row yet keeps
//                     its last goal; the first steps, until every agent had one, are all waits
//                     with 90% of the budget for rows), GD-RHCR's step-budget is 93% of it,
//                     less the rows' time, and RHCR's PBS timeout all of it, unless
//                     GDRHCR_PARAMS sets them
//   GDRHCR_TIMES_OUT  a file that gets our time per step in ms, one line per step (optional)
//   GDRHCR_SEED       seed for the planner's tie-breaks (default 0)
//   GDRHCR_DIST_MB    memory for distance rows (default 8192, or three quarters of the memory
//                     the machine has available at start-up when that is less:
//                     default_dist_budget_mb). When the rows of all the map's free cells fit in
//                     it, they are computed in the Start-Kit's preprocessing phase (within 80% of
//                     its limit): no step then waits for a row. Paris_1_256 (47,240 free cells,
//                     142 KB a rotation row) needs 6.4 GB, LoRR's warehouse_large 4.3 GB; a
//                     smaller value keeps rows to the goals in use
//   GDRHCR_PREP_DIR   offline preparation (gdrhcr/map_prep.hpp) cached in this directory: in the
//                     Start-Kit's preprocessing phase the adapter loads the file for this map,
//                     fleet size and model, or makes it (trials at the run's budget, of at
//                     most a third of the preprocessing limit and 10 minutes) and writes it
//                     there; its traffic cost applies unless GDRHCR_PARAMS sets one. Unset:
//                     no preparation. A bad file is reported on standard error and made again
//   GDRHCR_TURNS      mapf-wait (the planner's mapf steps with turns and waits,
//                     gdrhcr::MapfInRotation) or native (its own rotation planning); default
//                     gdrhcr::kLorrTurnPlanning
constexpr int kDistBudgetMb = 8192;  // GDRHCR_DIST_MB's default where the memory allows
constexpr int kStatsEvery = 500;     // steps between the planner's counters on standard error
struct BridgeOptions {
  std::string planner = "gd-rhcr";
  std::vector<std::pair<std::string, std::string>> params;
  double budget_ms = 0;
  std::string times_out;  // where our time per step goes (empty: nowhere)
  uint64_t seed = 0;
  std::string turns;  // "native" or "mapf-wait"; empty = gdrhcr::kLorrTurnPlanning
  int dist_budget_mb = kDistBudgetMb;
  std::string prep_dir;     // GDRHCR_PREP_DIR; empty = no offline preparation
  double preprocess_s = 0;  // the Start-Kit's preprocessing limit (0 = none given)
};
// Throws std::invalid_argument naming the variable for a malformed value.
BridgeOptions bridge_options_from_env();

// GDRHCR_DIST_MB when it is not set: kDistBudgetMb, or three quarters of `available_mb` (the
// memory the machine has available; 0 = unknown) when that is less, at least 1. So a machine
// with less memory than every cell's row needs computes rows as goals come instead of running
// out of memory.
int default_dist_budget_mb(uint64_t available_mb);
// MemAvailable in /proc/meminfo, in MB; 0 when it cannot be read.
uint64_t available_memory_mb();

// What the bridge did so far, for tests and reports.
struct BridgeStats {
  long steps = 0;
  long warm_up_steps = 0;   // all-wait steps while some agent had no goal with a row
  long over_budget = 0;     // steps that took longer than the budget (with one)
  uint64_t rows_precomputed = 0;      // distance rows computed before the first step
  uint64_t rows_before_planning = 0;  // distance rows computed in the row phase
  uint64_t rows_in_planner = 0;       // rows the planner had to compute itself (past its budget)
  uint64_t evictions = 0;             // rows the distance table dropped to keep its memory budget
};

// How far the planner's next step may run past the budget it is given (the work after its
// deadlines), for the adapter to plan for: the second largest overrun of the last kWindow steps
// (their 99th percentile). A lone slow step (the first, with its allocations) is forgotten, so it
// does not shrink the budgets of the hundreds of steps after it; an overrun that comes back more
// than once in kWindow steps is planned for, so at most about 1% of the steps run over.
class OverrunMemory {
 public:
  static constexpr int kWindow = 200;
  void add(double overrun_s);  // one step's overrun (negative: it ended early)
  double planned_s() const { return planned_; }

 private:
  std::vector<double> last_;
  size_t next_ = 0;
  double planned_ = 0;
};

class Bridge {
 public:
  // map[row * cols + col] = 1 for a blocked cell (the Start-Kit's env->map). Throws with a
  // message naming the problem (unknown planner or parameter, bad value).
  Bridge(int rows, int cols, const std::vector<int>& map, int num_agents, const BridgeOptions& options);
  ~Bridge();
  // One timestep within the Start-Kit's time_limit_s: locations and headings (0 east, 1 south,
  // 2 west, 3 north) of every agent and its revealed goal locations, current one first (empty:
  // no task). actions[i] gets the Start-Kit's Action value (0 FW, 1 CR, 2 CCR, 3 W). The
  // distance rows of new goals, if not all computed beforehand (GDRHCR_DIST_MB), are computed
  // first, within half the budget (30% of the limit without one); an agent whose goal has no
  // row yet keeps its last goal, and a step where some agent has none at all (the first of a
  // fleet of thousands) is all waits, its rows within 90% of the budget. A step that runs over
  // the budget is reported on stderr with its phases.
  void plan(int timestep, double time_limit_s, const std::vector<int>& locations, const std::vector<int>& headings,
            const std::vector<std::vector<int>>& goals, std::vector<int>& actions);
  BridgeStats stats() const;
  // The step costs of the world's rows (dist_table.hpp): those the planner's parameters resolve
  // to, with the step budget the adapter gives it.
  gdrhcr::StepCosts step_costs() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gdrhcr_lorr
