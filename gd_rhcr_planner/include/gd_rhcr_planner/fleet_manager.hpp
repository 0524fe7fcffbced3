// The fleet manager: everything the planner node does, without ROS. One tick gathers the robots'
// reports, dispatches tasks, plans, executes through the Action Dependency Graph (execution.hpp)
// and returns what to publish; between ticks it sends the moves that arrivals make ready. It also
// takes tasks, operator controls and live parameter changes, journals accepted tasks, and keeps
// the statistics and health the node reports. Thread-safe: inputs (reports, tasks, services) may
// come from any thread while tick() runs on the tick thread; the planner runs unlocked.
// planner_node.cpp converts messages to and from these plain structs; tested tick by tick in
// test/fleet_manager_test.cpp.
#pragma once

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "gd_rhcr_planner/deadline_planner.hpp"
#include "gd_rhcr_planner/dispatcher.hpp"
#include "gd_rhcr_planner/execution.hpp"
#include "gd_rhcr_planner/fleet.hpp"
#include "gd_rhcr_planner/fleet_stats.hpp"
#include "gd_rhcr_planner/fleet_view.hpp"
#include "gd_rhcr_planner/health.hpp"
#include "gd_rhcr_planner/operator_control.hpp"
#include "gd_rhcr_planner/task_store.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/params.hpp"
#include "gdrhcr/planner.hpp"

namespace gd_rhcr_planner {

using gdrhcr::Cell;

// The fleet manager's configuration: the node's private parameters (config/fleet.yaml).
struct FleetConfig {
  std::string planner = "gd-rhcr";
  gdrhcr::Params planner_params;  // the planner's own parameters, checked against its table
  int num_robots = 20;
  uint64_t seed = 1;
  double tick_rate = 2.0;         // Hz
  double plan_deadline = 0;       // s; 0 = 0.7 / tick_rate
  double offline_timeout = 2.0;   // s
  int commit_horizon = 2;         // ADG: committed, unfinished moves per robot
  int catch_up = 100;             // ADG: steps owed to a robot that lost time, late at a tick (0 = off)
  double dispatch_rate = 20.0;    // Hz: arrivals checked between ticks (0 = at ticks only)
  int dist_budget_mb = 256;
  std::string dispatcher = "batch";
  DispatchParams dispatch;
  std::string task_store;         // journal path; "" = off
  std::string action_model = "mapf";  // the robots' moves: mapf (any neighbour) or rotation (turns; issue 23)
  std::string prep_file;          // offline preparation (gdrhcr/map_prep.hpp); "" = none
  // Fills defaults (plan_deadline 0) and throws gdrhcr::ParamError naming a bad value.
  void validate();
  gdrhcr::ActionModel model() const;  // action_model parsed (after validate)
};

// The parameters dynamic_reconfigure changes (cfg/Planner.cfg); planner parameters the planner
// does not have are ignored.
struct LiveConfig {
  int V = 2, H = 20;
  double c_soft = 1.0;
  int K_threshold = 0;  // 0 = the planner's rule
  std::string solver = "pbs";
  double plan_deadline = 0, offline_timeout = 2.0;
  std::string dispatcher = "batch";
  int dispatch_switch_margin = 4, dispatch_finish_horizon = 10;
};

// GD-RHCR's step budget follows the plan deadline (this share of it) unless given explicitly.
constexpr double kStepBudgetShare = 0.9;

// The live planner parameters as the core reads them: those of `planner`'s table only.
gdrhcr::Params live_planner_params(const std::string& planner, const LiveConfig& c);

enum class LogLevel { kDebug, kInfo, kWarn, kError };

// One robot's report (gd_rhcr_msgs/RobotState) as the manager checks it.
struct RobotReport {
  int64_t id = 0;
  int x = 0, y = 0;
  uint8_t mode = 0;          // RobotState.MODE_*; MODE_OFFLINE takes the robot out
  bool moving = false;
  bool entering_known = false;  // moving into (entering_x, entering_y)
  int entering_x = 0, entering_y = 0;
  gdrhcr::Heading heading = gdrhcr::kNoHeading;  // the planner's numbering (action_model.hpp); kNoHeading: none
  double stamp = 0;          // the message's stamp (s); 0 = unstamped, not checked for order
  bool pose_finite = true;   // every pose field is a finite number
};

struct TaskRequest {
  int pickup_x = 0, pickup_y = 0, delivery_x = 0, delivery_y = 0, priority = 0;
  uint64_t id = 0;  // 0 = the manager picks one
};

struct RobotCommand {
  int robot = 0;
  Cell cell = gdrhcr::kNoCell;
  uint8_t mode = 0;   // RobotState.MODE_* after the move
  int64_t task = -1;
  gdrhcr::Heading heading = gdrhcr::kNoHeading;      // to face in `cell`; kNoHeading: any
  gdrhcr::Action action = gdrhcr::Action::kWait;    // from the pose the manager knows (command_action)
};

// One tick's figures (gd_rhcr_msgs/PlannerStats without the header).
struct TickStats {
  std::string planner, planner_config, planner_stats_json, dispatcher;
  uint32_t num_robots = 0, forced_waits = 0, tasks_queued = 0, tasks_active = 0, num_groups = 0;
  uint32_t offline_robots = 0, reconfigures = 0, group_size_max = 0, paused_robots = 0;
  bool planned = false, fallback = false, emergency_stop = false;
  double plan_time = 0, step_time = 0, tick_period = 0, deliveries_per_minute = 0, group_size_mean = 0;
  uint64_t overruns = 0, skipped_ticks = 0, tasks_delivered = 0, tasks_failed = 0, fallback_ticks = 0;
  PlannerFigures figures;
  DispatchStats dispatch;
};

struct TickResult {
  bool stepped = false;            // false: no command this tick (skip_reason)
  std::string skip_reason;
  uint64_t tick = 0;
  std::vector<RobotCommand> commands;
  std::vector<std::vector<int>> groups;     // robot ids per planner group (empty without groups)
  std::vector<std::string> group_solvers;
  TickStats stats;
  FleetView view;                  // filled when tick() is asked for it (rviz markers)
};

class FleetManager {
 public:
  using Log = std::function<void(LogLevel, const std::string&)>;
  // Builds the distance table, the planner (PIBT as its deadline fallback), the executor, the
  // dispatcher and the task store (restoring its open tasks). Throws gdrhcr::ParamError or
  // gdrhcr::MapError naming what is wrong.
  FleetManager(const gdrhcr::Grid& grid, FleetConfig cfg, Log sink = {});
  ~FleetManager();
  // Computes the distance rows of `cells` now (the map's pickup and delivery cells: the goals
  // tasks will name), in parallel, so the table does not grow while the fleet runs. Returns the
  // rows cached.
  size_t prepare_distances(const std::vector<Cell>& cells);

  // --- inputs (any thread) ---
  // Robots' reports of one message, received at `now` (the caller's clock, s). A report is
  // ignored (counted, its reason kept for diagnostics) when its robot is unknown, its cell is off
  // the map or on an obstacle, its mode is unknown, its pose is not finite, the same robot is in
  // the message twice, or it is stamped before the robot's last accepted report. Returns the
  // number ignored; `error`: the last reason.
  int update_robots(const std::vector<RobotReport>& reports, double now, std::string& error);
  bool update_robot(int64_t id, int x, int y, bool offline, bool moving, double now, std::string& error);
  SubmitResult submit(const TaskRequest& t);
  bool cancel(uint64_t task_id, std::string& reason);
  // Tasks (open ones, or all with finished), with their records.
  std::vector<std::pair<uint64_t, TaskRecord>> tasks(bool include_finished) const;
  // Task status changes since the last call, journaled before they are returned.
  std::vector<TaskEvent> take_events();
  int distance_left(uint64_t task_id) const;
  // Operator controls: "" or the reason it was refused.
  std::string set_paused(int64_t robot, bool paused);
  void set_emergency_stop(bool engage);
  std::string operator_summary() const;
  // Live tuning: checks `c` (a bad value is put back to the live one and named in the returned
  // errors) and builds the planner it needs; applied at the start of the next tick.
  std::vector<std::string> reconfigure(LiveConfig& c);
  LiveConfig live_config() const;

  // --- the tick thread ---
  // One tick at time `now` (the caller's clock, s; the clock of update_robot) and wall time
  // `wall` (s, for rates). `view`: also fill TickResult::view.
  TickResult tick(double now, double wall, bool view);
  // Between ticks: moves that arrivals since the last call made ready (commands of those robots).
  std::vector<RobotCommand> between_ticks();

  // --- reporting ---
  // The health and the figures for /diagnostics, as (name, value) pairs.
  Health diagnose(double wall, std::vector<std::pair<std::string, std::string>>& values);
  std::string planner_config_string() const;

  const gdrhcr::Grid& grid() const { return grid_; }
  const FleetConfig& config() const { return cfg_; }
  // The distance table's step costs (rotation: lanes, and the traffic cost of ~prep_file).
  const gdrhcr::StepCosts& step_costs() const { return dist_->step_costs(); }
  uint64_t tick_count() const;

 private:
  struct Gathered;
  Gathered gather_locked(double now, std::unique_ptr<DeadlinePlanner>& retired);
  void robot_records_locked(std::vector<RobotRecord>& robots, std::vector<uint8_t>& held) const;
  void place_unreported_locked(double now);
  void write_snapshot_locked(const TickOutput& exec) const;
  void read_snapshot();
  void apply_reconfigure_locked(std::unique_ptr<DeadlinePlanner>& retired);
  void release_stuck_locked(const TickOutput& exec, double now);
  void count_outcome_locked(const TickOutput& exec);
  std::vector<RobotCommand> commands_locked(const std::vector<Cell>& command, const std::vector<gdrhcr::Heading>& heading) const;
  void groups_of(const TickOutput& exec, const gdrhcr::Planner* primary, TickResult& out,
                 std::vector<int>& group_of) const;
  void stats_locked(const TickOutput& exec, const gdrhcr::Planner* primary, double step_time, double wall,
                    TickResult& out);
  void view_locked(const TickOutput& exec, const gdrhcr::Planner* primary, const std::vector<int>& group_of,
                      const std::vector<std::vector<Cell>>& goals, TickResult& out) const;
  void problem_locked(const std::string& what);
  std::string config_string_locked(const LiveConfig& c) const;
  void log(LogLevel level, const std::string& msg) const;
  void apply_prep(gdrhcr::Params& given) const;
  // At most one message per `key` every `period` seconds (steady clock).
  void log_every(const std::string& key, double period, LogLevel level, const std::string& msg);
  std::unique_ptr<DeadlinePlanner> make_deadline_planner(std::unique_ptr<gdrhcr::Planner> primary) const;

  const gdrhcr::Grid& grid_;
  FleetConfig cfg_;
  Log log_;
  bool auto_step_budget_ = false;
  gdrhcr::Params base_params_;  // the planner's parameters without the live ones

  std::unique_ptr<gdrhcr::DistTable> dist_;
  std::unique_ptr<DeadlinePlanner> planner_;  // the tick thread's (replaced at a tick's start)
  std::unique_ptr<Executor> executor_;        // the tick thread's

  mutable std::mutex mutex_;  // guards everything below
  std::unique_ptr<Fleet> fleet_;
  std::unique_ptr<TaskStore> store_;
  std::unique_ptr<Dispatcher> dispatcher_;
  OperatorControl operator_;
  DispatchStats dispatch_stats_;
  ThroughputMeter throughput_;
  HealthMonitor health_;
  LiveConfig live_, pending_;
  bool config_pending_ = false;
  std::unique_ptr<gdrhcr::Planner> pending_planner_;
  uint64_t tick_ = 0, overruns_ = 0, skipped_ = 0, invalid_plans_ = 0, bad_reports_ = 0;
  uint64_t fallback_ticks_ = 0, late_ticks_ = 0, planner_errors_ = 0, store_errors_ = 0;
  uint64_t early_dispatches_ = 0, catch_up_moves_ = 0, reconfigures_ = 0, stats_errors_ = 0;
  double first_report_ = 0;      // when the first robot reported (missing ones are waited for)
  std::deque<double> tick_walls_;  // wall times of recent ticks, for the measured rate
  double plan_time_sum_ = 0, plan_time_max_ = 0, step_time_max_ = 0, last_plan_time_ = 0;
  uint64_t plan_time_count_ = 0;
  std::string last_problem_;
  uint64_t last_problem_tick_ = 0;
  std::map<std::string, double> last_logged_;
  std::vector<double> last_stamp_;  // per robot: the stamp of its last accepted report
  std::vector<double> inconsistent_since_;  // per robot: when its reports stopped fitting (-1: they fit)
  std::string last_ignored_;        // why the last ignored report was ignored
  std::string snapshot_path_;       // the robots' cells for a successor (with the task store only)
  struct LastKnown {
    Cell cell = gdrhcr::kNoCell;
    bool moving = false;
    Cell entering = gdrhcr::kNoCell;  // the cell it was commanded into, while moving
    gdrhcr::Heading heading = gdrhcr::kNoHeading;
  };
  std::map<int, LastKnown> unreported_;  // from the snapshot: robot -> where it was last known
  uint64_t rejected_tasks_ = 0;
  std::string last_rejected_task_;
};

}  // namespace gd_rhcr_planner

namespace gd_rhcr_planner {

// Where a node keeps its task journal by default: $ROS_HOME (else ~/.ros)/gd_rhcr_planner/
// <node name>.tasks.jsonl, one per node, so planners in different namespaces keep their own.
std::string default_task_store(const std::string& node_name);

// The node's own private parameters (config/fleet.yaml), besides the planners'.
const std::vector<std::string>& node_param_names();
// What a private parameter of the node is: one of its own, one of `planner`'s (forwarded to it),
// or one of another planner's (ignored: config/fleet.yaml serves every planner). Throws
// gdrhcr::ParamError naming a parameter that is none of these (a misspelling).
enum class NodeParamKind { kNode, kPlanner, kOtherPlanner };
NodeParamKind classify_node_param(const std::string& name, const std::string& planner);

}  // namespace gd_rhcr_planner
