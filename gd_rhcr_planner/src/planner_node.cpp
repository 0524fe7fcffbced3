// gd_rhcr_planner_node: a thin ROS adapter over the planning core (src/). It loads the map,
// keeps the fleet's task bookkeeping (Fleet), and on every tick hands the robots' reports and
// goals to the execution layer (Executor, execution.hpp: liveness, planning from committed
// states, reservation, ADG commitment, validation) and publishes the commands it returns.
// Topics, services and parameters: gd_rhcr_planner/README.md.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <numeric>
#include <sstream>

#include <actionlib/server/action_server.h>
#include <diagnostic_msgs/DiagnosticArray.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <dynamic_reconfigure/server.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <gd_rhcr_msgs/CancelTask.h>
#include <gd_rhcr_msgs/EmergencyStop.h>
#include <gd_rhcr_msgs/SetPaused.h>
#include <gd_rhcr_planner/PlannerConfig.h>
#include <gd_rhcr_msgs/DeliveryAction.h>
#include <gd_rhcr_msgs/GroupArray.h>
#include <gd_rhcr_msgs/ListTasks.h>
#include <gd_rhcr_msgs/MapdCells.h>
#include <gd_rhcr_msgs/PlannerStats.h>
#include <gd_rhcr_msgs/RobotStateArray.h>
#include <gd_rhcr_msgs/StepCommandArray.h>
#include <gd_rhcr_msgs/SubmitTask.h>
#include <gd_rhcr_msgs/Task.h>
#include <gd_rhcr_msgs/TaskStatus.h>

#include <cstdlib>

#include "gd_rhcr_planner/deadline_planner.hpp"
#include "gd_rhcr_planner/dispatcher.hpp"
#include "gd_rhcr_planner/execution.hpp"
#include "gd_rhcr_planner/fleet_markers.hpp"
#include "gd_rhcr_planner/fleet_stats.hpp"
#include "gd_rhcr_planner/health.hpp"
#include "gd_rhcr_planner/operator_control.hpp"
#include "gd_rhcr_planner/fleet.hpp"
#include "gd_rhcr_planner/map_loader.hpp"
#include "gd_rhcr_planner/task_store.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/task_stream.hpp"
#include "gdrhcr/validator.hpp"

namespace gd_rhcr_planner {
namespace {

using gdrhcr::Cell;
using DeliveryServer = actionlib::ActionServer<gd_rhcr_msgs::DeliveryAction>;

std::string xmlrpc_to_string(XmlRpc::XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeInt: return std::to_string(static_cast<int>(v));
    case XmlRpc::XmlRpcValue::TypeDouble: {
      std::ostringstream s;
      s.precision(17);
      s << static_cast<double>(v);
      return s.str();
    }
    case XmlRpc::XmlRpcValue::TypeBoolean: return static_cast<bool>(v) ? "1" : "0";
    case XmlRpc::XmlRpcValue::TypeString: return static_cast<std::string>(v);
    default: throw gdrhcr::ParamError("planner parameter of unsupported type");
  }
}

class PlannerNode {
 public:
  PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh), pnh_(pnh) {}

  // Throws on a bad map or parameter (the node then exits with the message).
  void init();
  void start_timers(ros::CallbackQueue* tick_queue);

 private:
  void load_parameters();
  void publish_static();
  void on_states(const gd_rhcr_msgs::RobotStateArray::ConstPtr& msg);
  void on_task(const gd_rhcr_msgs::Task::ConstPtr& msg);
  bool on_submit(gd_rhcr_msgs::SubmitTask::Request& req, gd_rhcr_msgs::SubmitTask::Response& res);
  bool on_cancel(gd_rhcr_msgs::CancelTask::Request& req, gd_rhcr_msgs::CancelTask::Response& res);
  bool on_list(gd_rhcr_msgs::ListTasks::Request& req, gd_rhcr_msgs::ListTasks::Response& res);
  void on_goal(DeliveryServer::GoalHandle gh);
  void on_cancel_goal(DeliveryServer::GoalHandle gh);
  void on_tick(const ros::TimerEvent& ev);
  void on_dispatch(const ros::TimerEvent& ev);
  // Issue 14: operator services, live tuning, diagnostic_updater.
  bool on_set_paused(gd_rhcr_msgs::SetPaused::Request& req, gd_rhcr_msgs::SetPaused::Response& res);
  bool on_emergency_stop(gd_rhcr_msgs::EmergencyStop::Request& req, gd_rhcr_msgs::EmergencyStop::Response& res);
  void on_reconfigure(gd_rhcr_planner::PlannerConfig& config, uint32_t level);
  void apply_reconfigure_locked(std::unique_ptr<DeadlinePlanner>& retired);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  gdrhcr::Params planner_params_for(const gd_rhcr_planner::PlannerConfig& c) const;
  std::string planner_config_string(const gd_rhcr_planner::PlannerConfig& c) const;
  // GD-RHCR's step budget (--step-budget) follows the plan deadline unless set explicitly.
  bool auto_step_budget_ = false;
  static constexpr double kStepBudgetShare = 0.9;  // of the plan deadline
  static std::string step_budget_string(double plan_deadline);

  // A tick's parts (on_tick); those named _locked with mutex_ held.
  struct TickInput {
    uint64_t tick = 0;
    std::vector<std::vector<Cell>> goals;  // per robot (Fleet::fill_goals)
    std::vector<uint8_t> held;             // per robot: paused or stopped, no new move
    std::vector<RobotRecord> robots;
    bool proceed_without_missing = false;
  };
  TickInput gather_tick_locked(std::unique_ptr<DeadlinePlanner>& retired);
  void robot_records_locked(std::vector<RobotRecord>& robots, std::vector<uint8_t>& held) const;
  gd_rhcr_msgs::GroupArray group_message(const TickOutput& exec, const gdrhcr::Planner* primary,
                                         std::vector<int>& group_of) const;
  void count_outcome_locked(const TickOutput& exec, uint64_t tick);
  void publish_commands_locked(const std::vector<Cell>& command, uint64_t tick, const ros::Time& stamp,
                               bool between_ticks = false);
  double record_timing_locked(std::chrono::steady_clock::time_point wall0, uint64_t tick,
                              const gdrhcr::StepReport& report);
  void publish_stats_locked(const TickOutput& exec, const gdrhcr::Planner* primary,
                            const gd_rhcr_msgs::GroupArray& groups_msg, uint64_t tick, const ros::Time& stamp,
                            double step_time);

  // With mutex_ held.
  void publish_events_locked();
  void publish_markers_locked(const std::vector<Cell>& pos, const std::vector<Cell>& next,
                              const std::vector<std::vector<Cell>>& goals,
                              const std::vector<int>& group_of,
                              const std::vector<std::vector<Cell>>& planned_paths);
  geometry_msgs::Pose pose_of(Cell c) const;
  geometry_msgs::Point point_of(Cell c, double z) const;

  std::string default_task_store() const;

  ros::NodeHandle nh_, pnh_;
  // Parameters.
  std::string map_path_, planner_name_, frame_id_, task_store_path_;
  double cell_size_ = 1.0, tick_rate_ = 2.0, plan_deadline_ = 0, offline_timeout_ = 2.0;
  int num_robots_ = 0, label_limit_ = 60, dist_budget_mb_ = 256;
  uint64_t seed_ = 1;
  bool per_robot_topics_ = false, publish_markers_ = true, show_goal_lines_ = false;
  gdrhcr::Params planner_params_;
  std::string dispatcher_name_ = "batch";
  DispatchParams dispatch_params_;

  // The core.
  std::unique_ptr<LoadedMap> map_;
  std::unique_ptr<gdrhcr::DistTable> dist_;
  std::unique_ptr<DeadlinePlanner> planner_;
  std::unique_ptr<Fleet> fleet_;
  std::unique_ptr<TaskStore> store_;  // null when persistence is off
  gdrhcr::MapdCells mapd_;

  std::mutex mutex_;  // guards fleet_, goal handles, counters below
  std::map<uint64_t, DeliveryServer::GoalHandle> goal_of_task_;
  uint64_t tick_ = 0, overruns_ = 0, skipped_ = 0, invalid_plans_ = 0, bad_reports_ = 0;
  uint64_t fallback_ticks_ = 0, late_ticks_ = 0, planner_errors_ = 0, store_errors_ = 0;
  // Issue 13: the execution layer (the ADG), used by the tick thread only.
  std::string execution_ = "adg";
  int commit_horizon_ = 2;
  double dispatch_rate_ = 20.0;  // Hz: arrivals checked between ticks (adg), 0 = at ticks only
  uint64_t early_dispatches_ = 0;  // moves dispatched between ticks
  std::unique_ptr<Executor> executor_;
  double first_report_s_ = 0;  // when the first robot reported (missing robots are waited for a while)
  std::deque<double> tick_stamps_;  // wall times of recent published ticks, for the rate
  double plan_time_sum_ = 0, plan_time_max_ = 0, step_time_max_ = 0, last_plan_time_ = 0;
  int plan_time_count_ = 0;
  std::string last_problem_;  // the latest problem, kept after it is over (see its tick)
  uint64_t last_problem_tick_ = 0;

  // Issue 14. Guarded by mutex_ unless noted.
  std::unique_ptr<Dispatcher> dispatcher_;
  DispatchStats dispatch_stats_;
  std::unique_ptr<OperatorControl> operator_;
  std::unique_ptr<FleetMarkers> markers_;
  ThroughputMeter throughput_;
  HealthMonitor health_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;  // main thread
  double tick_freq_min_ = 0, tick_freq_max_ = 0;
  std::unique_ptr<diagnostic_updater::FrequencyStatus> tick_freq_;  // internally locked
  std::unique_ptr<diagnostic_updater::TimeStampStatus> tick_stamp_;  // internally locked
  std::unique_ptr<dynamic_reconfigure::Server<gd_rhcr_planner::PlannerConfig>> reconfigure_;
  boost::recursive_mutex reconfigure_mutex_;
  gd_rhcr_planner::PlannerConfig live_config_;     // what the node runs with
  bool config_pending_ = false;                    // a change waits for the next tick
  gd_rhcr_planner::PlannerConfig pending_config_;
  std::unique_ptr<gdrhcr::Planner> pending_planner_;  // built by on_reconfigure, swapped in by on_tick
  uint64_t reconfigures_ = 0;
  gdrhcr::Params base_params_;  // planner parameters from the start, without the reconfigurable ones

  ros::Publisher commands_pub_, updates_pub_, status_pub_, map_pub_, mapd_pub_, markers_pub_, stats_pub_,
      groups_pub_;
  std::vector<ros::Publisher> robot_pubs_;
  ros::Subscriber states_sub_, tasks_sub_;
  ros::ServiceServer submit_srv_, cancel_srv_, list_srv_, pause_srv_, estop_srv_;
  std::unique_ptr<DeliveryServer> action_;
  ros::Timer tick_timer_, diag_timer_, dispatch_timer_;
  ros::WallTime started_ = ros::WallTime::now();
};

void PlannerNode::load_parameters() {
  if (!pnh_.getParam("map", map_path_) || map_path_.empty())
    throw gdrhcr::ParamError("parameter ~map (path of a .map, kiva .map or map_server .yaml) is required");
  pnh_.param("planner", planner_name_, std::string("pibt"));
  pnh_.param("frame_id", frame_id_, std::string("map"));
  pnh_.param("cell_size", cell_size_, 1.0);
  pnh_.param("tick_rate", tick_rate_, 2.0);
  pnh_.param("num_robots", num_robots_, 10);
  int seed = 1;
  pnh_.param("seed", seed, 1);
  seed_ = static_cast<uint64_t>(seed);
  pnh_.param("per_robot_topics", per_robot_topics_, false);
  pnh_.param("publish_markers", publish_markers_, true);
  pnh_.param("label_limit", label_limit_, 60);
  pnh_.param("dist_budget_mb", dist_budget_mb_, 256);
  pnh_.param("plan_deadline", plan_deadline_, 0.0);
  pnh_.param("offline_timeout", offline_timeout_, 2.0);
  pnh_.param("execution", execution_, std::string("adg"));    // issue 13: adg, the only execution
  pnh_.param("commit_horizon", commit_horizon_, 2);
  pnh_.param("dispatch_rate", dispatch_rate_, 20.0);
  pnh_.param("show_goal_lines", show_goal_lines_, false);
  pnh_.param("dispatcher", dispatcher_name_, std::string("batch"));
  parse_dispatch_policy(dispatcher_name_);  // throws naming a bad value
  pnh_.param("dispatch_finish_horizon", dispatch_params_.finish_horizon, dispatch_params_.finish_horizon);
  pnh_.param("dispatch_switch_margin", dispatch_params_.switch_margin, dispatch_params_.switch_margin);
  pnh_.param("dispatch_max_tasks", dispatch_params_.max_tasks, dispatch_params_.max_tasks);
  pnh_.param("dispatch_age_weight", dispatch_params_.age_weight, dispatch_params_.age_weight);
  dispatch_params_.validate();
  if (!pnh_.getParam("task_store", task_store_path_) || task_store_path_ == "default")
    task_store_path_ = default_task_store();
  if (task_store_path_ == "none") task_store_path_.clear();
  if (!(tick_rate_ > 0 && tick_rate_ <= 1000)) throw gdrhcr::ParamError("~tick_rate must be in (0, 1000] Hz");
  if (plan_deadline_ == 0) plan_deadline_ = 0.7 / tick_rate_;
  if (!(plan_deadline_ > 0 && plan_deadline_ <= 1.0 / tick_rate_))
    throw gdrhcr::ParamError("~plan_deadline must be in (0, 1/tick_rate] seconds (0 = 0.7/tick_rate)");
  if (!(offline_timeout_ > 0)) throw gdrhcr::ParamError("~offline_timeout must be > 0 seconds");
  if (!(dispatch_rate_ >= 0 && dispatch_rate_ <= 1000))
    throw gdrhcr::ParamError("~dispatch_rate must be in [0, 1000] Hz (0 = moves are dispatched at ticks only)");
  if (num_robots_ < 1) throw gdrhcr::ParamError("~num_robots must be >= 1");
  if (!(cell_size_ > 0)) throw gdrhcr::ParamError("~cell_size must be > 0 metres");
  if (dist_budget_mb_ < 1) throw gdrhcr::ParamError("~dist_budget_mb must be >= 1");

  // Planner parameters under their ROS names (the core reads c_soft as c-soft, K_threshold as
  // k-threshold), then anything in ~planner_params. K_threshold 0 means the planner's default.
  for (const char* name : {"V", "H", "c_soft", "K_threshold", "alpha", "timeout", "threads", "node_budget"}) {
    XmlRpc::XmlRpcValue v;
    if (!pnh_.getParam(name, v)) continue;
    if (std::string(name) == "K_threshold" && v.getType() == XmlRpc::XmlRpcValue::TypeInt && static_cast<int>(v) == 0)
      continue;
    planner_params_.set(name, xmlrpc_to_string(v));
    const std::string n(name);
    if (n != "V" && n != "H" && n != "c_soft" && n != "K_threshold") base_params_.set(name, xmlrpc_to_string(v));
  }
  XmlRpc::XmlRpcValue extra;
  if (pnh_.getParam("planner_params", extra) && extra.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
    for (auto it = extra.begin(); it != extra.end(); ++it) {
      planner_params_.set(it->first, xmlrpc_to_string(it->second));
      const std::string c = gdrhcr::Params::canonical(it->first);
      if (c != "solver" && c != "solver2") base_params_.set(it->first, xmlrpc_to_string(it->second));
    }
  }
  // GD-RHCR returns within 90% of the plan deadline (issue 12's step budget: groups it cannot
  // solve in time are moved by its secondary solver, counted as budget_skips), so the node's
  // PIBT moves the whole fleet only when even that is late. An explicit step_budget wins.
  auto_step_budget_ = planner_name_ == "gd-rhcr" && !planner_params_.has("step-budget");
  if (auto_step_budget_) planner_params_.set("step-budget", step_budget_string(plan_deadline_));
  // The live values (dynamic_reconfigure starts from the same parameters).
  live_config_ = gd_rhcr_planner::PlannerConfig::__getDefault__();
  pnh_.getParam("V", live_config_.V);
  pnh_.getParam("H", live_config_.H);
  pnh_.getParam("c_soft", live_config_.c_soft);
  pnh_.getParam("K_threshold", live_config_.K_threshold);
  if (extra.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
    if (extra.hasMember("solver")) live_config_.solver = xmlrpc_to_string(extra["solver"]);
    if (extra.hasMember("solver2")) live_config_.solver2 = xmlrpc_to_string(extra["solver2"]);
  }
  pnh_.getParam("solver", live_config_.solver);
  pnh_.getParam("solver2", live_config_.solver2);
  live_config_.plan_deadline = plan_deadline_;
  live_config_.offline_timeout = offline_timeout_;
  live_config_.dispatcher = dispatcher_name_;
  live_config_.dispatch_switch_margin = dispatch_params_.switch_margin;
  live_config_.dispatch_finish_horizon = dispatch_params_.finish_horizon;
}

// $ROS_HOME (else ~/.ros)/gd_rhcr_planner/<node name>.tasks.jsonl: one store per planner node,
// so planners in different namespaces keep their own queues.
std::string PlannerNode::default_task_store() const {
  std::string home;
  if (const char* h = std::getenv("ROS_HOME")) home = h;
  else if (const char* u = std::getenv("HOME")) home = std::string(u) + "/.ros";
  else home = "/tmp";
  std::string name = ros::this_node::getName();
  std::replace(name.begin(), name.end(), '/', '_');
  if (!name.empty() && name[0] == '_') name.erase(0, 1);
  return home + "/gd_rhcr_planner/" + name + ".tasks.jsonl";
}

void PlannerNode::init() {
  load_parameters();
  map_ = std::make_unique<LoadedMap>(load_map(map_path_, cell_size_));
  const auto& grid = map_->grid;
  if (static_cast<size_t>(num_robots_) > grid.free_cells().size())
    throw gdrhcr::ParamError("~num_robots exceeds the free cells of the map");
  dist_ = std::make_unique<gdrhcr::DistTable>(grid, size_t(dist_budget_mb_) << 20);
  gdrhcr::Params no_params;
  planner_ = std::make_unique<DeadlinePlanner>(
      gdrhcr::make_planner(planner_name_, planner_params_, grid, num_robots_, seed_),
      gdrhcr::make_planner("pibt", no_params, grid, num_robots_, seed_));
  const auto unused = planner_params_.unused();
  if (!unused.empty()) {
    std::string s;
    for (auto& u : unused) s += (s.empty() ? "" : ", ") + u;
    ROS_INFO("planner '%s' does not use parameters: %s", planner_name_.c_str(), s.c_str());
  }
  fleet_ = std::make_unique<Fleet>(grid, *dist_, num_robots_);
  {  // the per-tick execution layer (issue 13): throws ParamError on a bad ~execution/~commit_horizon
    if (execution_ != "adg")
      throw gdrhcr::ParamError("~execution: 'adg' is the only execution (lock-step was removed in issue 22), not '" +
                               execution_ + "'");
    ExecutorConfig ec;
    ec.commit_horizon = commit_horizon_;
    ec.plan_deadline_s = plan_deadline_;
    ec.dist_budget_bytes = size_t(dist_budget_mb_) << 20;
    executor_ = std::make_unique<Executor>(grid, *dist_, num_robots_, ec);
  }
  dispatcher_ = std::make_unique<Dispatcher>(parse_dispatch_policy(dispatcher_name_), dispatch_params_);
  fleet_->set_auto_assign(false);  // the dispatcher assigns (both policies)
  operator_ = std::make_unique<OperatorControl>(num_robots_);
  if (!task_store_path_.empty()) {
    store_ = std::make_unique<TaskStore>(task_store_path_);  // throws on a damaged store
    const auto& saved = store_->loaded();
    for (auto& w : saved.warnings) ROS_WARN("%s", w.c_str());
    const size_t n = fleet_->restore(saved.open, saved.delivered, saved.failed, saved.next_id);
    ROS_INFO("task store %s: %zu open tasks restored (%zu in the store)", task_store_path_.c_str(), n,
             saved.open.size());
  } else {
    ROS_INFO("task store off (~task_store: none): tasks do not survive a restart");
  }
  mapd_ = map_->format == "map_server" ? gdrhcr::default_mapd_cells(grid)
                                       : gdrhcr::mapd_cells_for_map(grid, map_path_);
  ROS_INFO("map %s (%s, %dx%d, %zu free cells, %.3f m/cell); planner %s; %d robots; tick %.2f Hz; "
           "%zu pickups, %zu deliveries",
           map_path_.c_str(), map_->format.c_str(), grid.width(), grid.height(), grid.free_cells().size(),
           map_->frame.resolution, planner_name_.c_str(), num_robots_, tick_rate_, mapd_.pickups.size(),
           mapd_.deliveries.size());

  commands_pub_ = nh_.advertise<gd_rhcr_msgs::StepCommandArray>("step_commands", 10);
  // Between ticks (adg): the commands of the robots just given a move, nobody else's.
  updates_pub_ = nh_.advertise<gd_rhcr_msgs::StepCommandArray>("step_command_updates", 100);
  status_pub_ = nh_.advertise<gd_rhcr_msgs::TaskStatus>("task_status", 1000);
  map_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
  mapd_pub_ = nh_.advertise<gd_rhcr_msgs::MapdCells>("mapd_cells", 1, true);
  stats_pub_ = nh_.advertise<gd_rhcr_msgs::PlannerStats>("planner_stats", 10);
  groups_pub_ = nh_.advertise<gd_rhcr_msgs::GroupArray>("planner_groups", 10);
  // Markers are sent as changes; a new subscriber first gets the whole picture (not latched: a
  // latched message would be the last change only).
  markers_pub_ = nh_.advertise<visualization_msgs::MarkerArray>(
      "fleet_markers", 1, [this](const ros::SingleSubscriberPublisher& sub) {
        std::lock_guard<std::mutex> lock(mutex_);
        if (!markers_ || markers_->current().empty()) return;
        visualization_msgs::MarkerArray all;
        all.markers = markers_->current();
        sub.publish(all);
      }, ros::SubscriberStatusCallback(), ros::VoidConstPtr(), false);
  MarkerStyle style;
  style.frame_id = frame_id_;
  style.label_limit = label_limit_;
  style.show_goal_lines = show_goal_lines_;
  markers_ = std::make_unique<FleetMarkers>(grid, map_->frame, style);
  markers_->set_stations(mapd_.pickups, mapd_.deliveries);
  // diagnostic_updater on /diagnostics: the planner's health and the tick's frequency and stamps.
  updater_ = std::make_unique<diagnostic_updater::Updater>();
  updater_->setHardwareID("gd_rhcr_fleet" + nh_.getNamespace());
  updater_->add("planner", this, &PlannerNode::diagnose);
  tick_freq_min_ = 0.9 * tick_rate_;
  tick_freq_max_ = 1.1 * tick_rate_;
  tick_freq_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      diagnostic_updater::FrequencyStatusParam(&tick_freq_min_, &tick_freq_max_, 0.05, 10), "tick rate");
  tick_stamp_ = std::make_unique<diagnostic_updater::TimeStampStatus>(
      diagnostic_updater::TimeStampStatusParam(-1.0, 1.0 / tick_rate_ + 0.1), "tick stamps");
  updater_->add(*tick_freq_);
  updater_->add(*tick_stamp_);
  pause_srv_ = nh_.advertiseService("set_paused", &PlannerNode::on_set_paused, this);
  estop_srv_ = nh_.advertiseService("emergency_stop", &PlannerNode::on_emergency_stop, this);
  if (per_robot_topics_)
    for (int r = 0; r < num_robots_; ++r)
      robot_pubs_.push_back(
          nh_.advertise<gd_rhcr_msgs::StepCommand>("robot_" + std::to_string(r) + "/step_command", 10));
  states_sub_ = nh_.subscribe("robot_states", 10, &PlannerNode::on_states, this);
  tasks_sub_ = nh_.subscribe("tasks", 1000, &PlannerNode::on_task, this);
  submit_srv_ = nh_.advertiseService("submit_task", &PlannerNode::on_submit, this);
  cancel_srv_ = nh_.advertiseService("cancel_task", &PlannerNode::on_cancel, this);
  list_srv_ = nh_.advertiseService("list_tasks", &PlannerNode::on_list, this);
  action_ = std::make_unique<DeliveryServer>(
      nh_, "delivery", [this](DeliveryServer::GoalHandle gh) { on_goal(gh); },
      [this](DeliveryServer::GoalHandle gh) { on_cancel_goal(gh); }, false);
  action_->start();
  publish_static();
}

void PlannerNode::start_timers(ros::CallbackQueue* tick_queue) {
  ros::TimerOptions opts(ros::Duration(1.0 / tick_rate_),
                         [this](const ros::TimerEvent& ev) { on_tick(ev); }, tick_queue);
  tick_timer_ = nh_.createTimer(opts);
  if (dispatch_rate_ > 0) {
    // On the tick thread, so it never runs during a tick (the executor is the tick thread's).
    ros::TimerOptions d(ros::Duration(1.0 / dispatch_rate_),
                        [this](const ros::TimerEvent& ev) { on_dispatch(ev); }, tick_queue);
    dispatch_timer_ = nh_.createTimer(d);
  }
  diag_timer_ = nh_.createTimer(ros::Duration(0.25), [this](const ros::TimerEvent&) { updater_->update(); });
  // Live tuning; the first callback brings the server's starting values (the same parameters).
  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<gd_rhcr_planner::PlannerConfig>>(reconfigure_mutex_, pnh_);
  reconfigure_->setCallback([this](gd_rhcr_planner::PlannerConfig& c, uint32_t level) { on_reconfigure(c, level); });
}

geometry_msgs::Pose PlannerNode::pose_of(Cell c) const {
  geometry_msgs::Pose p;
  p.position = point_of(c, 0.0);
  p.orientation.w = 1.0;
  return p;
}

geometry_msgs::Point PlannerNode::point_of(Cell c, double z) const {
  geometry_msgs::Point p;
  p.x = map_->frame.world_x(map_->grid.x_of(c));
  p.y = map_->frame.world_y(map_->grid.y_of(c));
  p.z = z;
  return p;
}

void PlannerNode::publish_static() {
  const auto& grid = map_->grid;
  nav_msgs::OccupancyGrid og;
  og.header.frame_id = frame_id_;
  og.header.stamp = ros::Time::now();
  og.info.map_load_time = og.header.stamp;
  og.info.resolution = static_cast<float>(map_->frame.resolution);
  og.info.width = grid.width();
  og.info.height = grid.height();
  og.info.origin.position.x = map_->frame.origin_x;
  og.info.origin.position.y = map_->frame.origin_y;
  og.info.origin.orientation.w = 1.0;
  og.data.resize(static_cast<size_t>(grid.width()) * grid.height());
  for (int r = 0; r < grid.height(); ++r)
    for (int x = 0; x < grid.width(); ++x)
      og.data[static_cast<size_t>(r) * grid.width() + x] =
          grid.is_free(grid.cell(x, grid.height() - 1 - r)) ? 0 : 100;
  map_pub_.publish(og);

  gd_rhcr_msgs::MapdCells mc;
  mc.header = og.header;
  mc.rule = mapd_.rule;
  for (Cell c : mapd_.pickups) mc.pickup_x.push_back(grid.x_of(c)), mc.pickup_y.push_back(grid.y_of(c));
  for (Cell c : mapd_.deliveries)
    mc.delivery_x.push_back(grid.x_of(c)), mc.delivery_y.push_back(grid.y_of(c));
  mapd_pub_.publish(mc);
}

void PlannerNode::on_states(const gd_rhcr_msgs::RobotStateArray::ConstPtr& msg) {
  const double now = ros::Time::now().toSec();
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& s : msg->robots) {
    std::string error;
    if (!fleet_->update_robot(s.id, s.x, s.y, s.mode == kOffline, s.moving, error, now)) {
      ++bad_reports_;
      ROS_WARN_THROTTLE(2.0, "ignoring robot state: %s", error.c_str());
    }
  }
}

void PlannerNode::on_task(const gd_rhcr_msgs::Task::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto r = fleet_->submit(msg->pickup_x, msg->pickup_y, msg->delivery_x, msg->delivery_y, msg->priority, msg->id);
  if (!r.accepted) ROS_WARN("task %lu rejected: %s", (unsigned long)r.task_id, r.reason.c_str());
  publish_events_locked();
}

bool PlannerNode::on_submit(gd_rhcr_msgs::SubmitTask::Request& req, gd_rhcr_msgs::SubmitTask::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto& t = req.task;
  auto r = fleet_->submit(t.pickup_x, t.pickup_y, t.delivery_x, t.delivery_y, t.priority, t.id);
  res.accepted = r.accepted;
  res.task_id = r.task_id;
  res.reason = r.reason;
  if (!r.accepted) ROS_WARN("task %lu rejected: %s", (unsigned long)r.task_id, r.reason.c_str());
  publish_events_locked();
  return true;
}

bool PlannerNode::on_cancel(gd_rhcr_msgs::CancelTask::Request& req, gd_rhcr_msgs::CancelTask::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  res.success = fleet_->cancel(req.task_id, res.reason);
  publish_events_locked();
  return true;
}

bool PlannerNode::on_list(gd_rhcr_msgs::ListTasks::Request& req, gd_rhcr_msgs::ListTasks::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [id, t] : fleet_->tasks()) {
    if (!req.include_finished && task_finished(t.state)) continue;
    gd_rhcr_msgs::Task m;
    m.id = id;
    m.pickup_x = t.pickup_x, m.pickup_y = t.pickup_y;
    m.delivery_x = t.delivery_x, m.delivery_y = t.delivery_y;
    m.priority = t.priority;
    gd_rhcr_msgs::TaskStatus s;
    s.task_id = id;
    s.state = t.state;
    s.robot_id = t.robot;
    s.reason = t.reason;
    res.tasks.push_back(m);
    res.statuses.push_back(s);
  }
  return true;
}

void PlannerNode::on_goal(DeliveryServer::GoalHandle gh) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto g = gh.getGoal();
  auto r = fleet_->submit(g->pickup_x, g->pickup_y, g->delivery_x, g->delivery_y, g->priority, 0);
  if (!r.accepted) {
    gd_rhcr_msgs::DeliveryResult res;
    res.final_state = kFailed;
    res.reason = r.reason;
    res.task_id = r.task_id;
    res.robot_id = -1;
    gh.setRejected(res, r.reason);
    ROS_WARN("delivery goal rejected: %s", r.reason.c_str());
    publish_events_locked();
    return;
  }
  gh.setAccepted();
  goal_of_task_.emplace(r.task_id, gh);
  publish_events_locked();
}

void PlannerNode::on_cancel_goal(DeliveryServer::GoalHandle gh) {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [task, handle] : goal_of_task_) {
    if (!(handle == gh)) continue;
    std::string reason;
    fleet_->cancel(task, reason);  // the CANCELLED event finishes the goal below
    break;
  }
  publish_events_locked();
}

void PlannerNode::publish_events_locked() {
  const ros::Time now = ros::Time::now();
  const auto events = fleet_->take_events();
  if (store_ && !events.empty()) {
    try {  // before anyone hears of the change, so an accepted task is on disk when accepted
      store_->record(events, *fleet_);
    } catch (const std::exception& e) {
      ++store_errors_;
      last_problem_ = e.what();
      last_problem_tick_ = tick_;
      ROS_ERROR_THROTTLE(2.0, "%s; tasks are kept in memory but will not survive a restart", e.what());
    }
  }
  for (auto& e : events) {
    gd_rhcr_msgs::TaskStatus st;
    st.header.stamp = now;
    st.task_id = e.task_id;
    st.state = e.state;
    st.robot_id = e.robot;
    st.reason = e.reason;
    status_pub_.publish(st);
    if (e.state == kFailed || e.state == kCancelled)
      ROS_INFO("task %lu %s%s%s", (unsigned long)e.task_id, task_state_name(e.state),
               e.reason.empty() ? "" : ": ", e.reason.c_str());
    auto it = goal_of_task_.find(e.task_id);
    if (it == goal_of_task_.end()) continue;
    auto& gh = it->second;
    if (task_finished(e.state)) {
      gd_rhcr_msgs::DeliveryResult res;
      res.final_state = e.state;
      res.reason = e.reason;
      res.task_id = e.task_id;
      res.robot_id = e.robot;
      if (e.state == kDelivered) gh.setSucceeded(res);
      else if (e.state == kCancelled) gh.setCanceled(res, e.reason);
      else gh.setAborted(res, e.reason);
      goal_of_task_.erase(it);
    } else {
      gd_rhcr_msgs::DeliveryFeedback fb;
      fb.state = e.state;
      fb.robot_id = e.robot;
      fb.task_id = e.task_id;
      fb.distance_left = fleet_->distance_left(e.task_id);
      gh.publishFeedback(fb);
    }
  }
}

// One tick: gather the fleet's state and dispatch tasks (locked), run the execution layer
// (unlocked, so services and state updates keep flowing), then publish and count (locked).
void PlannerNode::on_tick(const ros::TimerEvent& ev) {
  const auto wall0 = std::chrono::steady_clock::now();
  std::unique_ptr<DeadlinePlanner> retired;  // a planner replaced by reconfigure, destroyed unlocked
  TickInput in;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    in = gather_tick_locked(retired);
  }
  // Liveness, planning, reservation, commitment and validation: the execution layer (the ADG,
  // execution.hpp).
  executor_->set_plan_deadline(plan_deadline_);
  const TickOutput exec = executor_->tick(in.robots, in.goals, *planner_, in.proceed_without_missing, &in.held);
  if (!exec.stepped) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++skipped_;
    last_problem_ = exec.skip_reason;
    last_problem_tick_ = tick_;
    ROS_INFO_THROTTLE(5.0, "no step: %s", last_problem_.c_str());
    return;
  }
  for (const std::string& w : exec.warnings) ROS_WARN("%s", w.c_str());

  // The primary planner's groups and paths, when it planned this tick (else it may still be
  // running an abandoned step on its worker and must not be read).
  const gdrhcr::Planner* primary = exec.outcome.fallback ? nullptr : &planner_->primary();
  std::vector<int> group_of;
  gd_rhcr_msgs::GroupArray groups_msg = group_message(exec, primary, group_of);
  std::vector<std::vector<Cell>> planned;
  if (primary && publish_markers_) {
    planned.resize(exec.cells.size());
    for (size_t a = 0; a < exec.robot_of_agent.size(); ++a)
      planned[exec.robot_of_agent[a]] = primary->planned_path(static_cast<int>(a));
  }

  std::lock_guard<std::mutex> lock(mutex_);
  count_outcome_locked(exec, in.tick);
  const ros::Time stamp = ev.current_real.isZero() ? ros::Time::now() : ev.current_real;
  publish_commands_locked(exec.command, in.tick, stamp);
  const double step_time = record_timing_locked(wall0, in.tick, exec.outcome.report);
  publish_stats_locked(exec, primary, groups_msg, in.tick, stamp, step_time);
  if (!groups_msg.groups.empty()) {
    groups_msg.header.stamp = stamp;
    groups_msg.header.frame_id = frame_id_;
    groups_msg.tick = in.tick;
    groups_pub_.publish(groups_msg);
  }
  if (publish_markers_) publish_markers_locked(exec.cells, exec.command, in.goals, group_of, planned);
  if (retired) ROS_DEBUG("tick %lu: previous planner retired", (unsigned long)in.tick);
}

// Between ticks (adg): robots that reported arrival let the robots queued behind them go at once
// (Executor::advance); only their new commands are published, on step_command_updates (and their
// own topics), with the last tick's number.
void PlannerNode::on_dispatch(const ros::TimerEvent& ev) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (tick_ == 0) return;
  std::vector<RobotRecord> robots;
  std::vector<uint8_t> held;
  robot_records_locked(robots, held);
  const std::vector<int> changed = executor_->advance(robots, &held);
  if (changed.empty()) return;
  early_dispatches_ += changed.size();
  std::vector<Cell> command(fleet_->num_robots(), gdrhcr::kNoCell);
  for (int r : changed) command[r] = executor_->command(r);
  publish_commands_locked(command, tick_, ev.current_real.isZero() ? ros::Time::now() : ev.current_real, true);
}

// The start of a tick: a pending reconfigure, silent robots, the wait for robots that never
// reported, task dispatch, and a copy of what the execution layer needs.
PlannerNode::TickInput PlannerNode::gather_tick_locked(std::unique_ptr<DeadlinePlanner>& retired) {
  TickInput in;
  in.tick = ++tick_;
  apply_reconfigure_locked(retired);
  for (int r : fleet_->mark_silent(ros::Time::now().toSec(), offline_timeout_))
    ROS_WARN("robot %d sent no state for %.1f s: offline (an obstacle at its last cell); its task is requeued",
             r, offline_timeout_);
  // Robots that never reported are waited for ~offline_timeout after the first report, then
  // left out (taken to be off the floor); the rest of the fleet moves (issue 13).
  const double now_s = ros::Time::now().toSec();
  const int missing = fleet_->missing_robots();
  if (missing < fleet_->num_robots() && first_report_s_ == 0) first_report_s_ = now_s;
  in.proceed_without_missing = first_report_s_ > 0 && now_s - first_report_s_ >= offline_timeout_;
  if (missing > 0 && in.proceed_without_missing) {
    last_problem_ = std::to_string(missing) + " robots never reported a state: left out of planning";
    last_problem_tick_ = tick_;
    ROS_WARN_THROTTLE(10.0, "%s", last_problem_.c_str());
  }
  // Tasks move on only once the fleet does (every robot reported, or the wait for the missing
  // ones is over): before, robots without a cell must not be assigned anything.
  if (missing == 0 || in.proceed_without_missing) {
    fleet_->advance();
    dispatch_stats_ = dispatcher_->dispatch(*fleet_, *dist_, operator_->unavailable());
  }
  publish_events_locked();
  fleet_->fill_goals(in.goals);
  robot_records_locked(in.robots, in.held);
  return in;
}

// What the execution layer gets of each robot: its record, and whether it is held (paused,
// emergency stop: no new move).
void PlannerNode::robot_records_locked(std::vector<RobotRecord>& robots, std::vector<uint8_t>& held) const {
  robots.clear();
  robots.reserve(fleet_->num_robots());
  held.assign(fleet_->num_robots(), 0);
  for (int r = 0; r < fleet_->num_robots(); ++r) {
    robots.push_back(fleet_->robot(r));
    held[r] = operator_->holds(r);
  }
}

// The planner's groups by robot id (group_of: each robot's group; a robot alone when the
// planner gave none).
gd_rhcr_msgs::GroupArray PlannerNode::group_message(const TickOutput& exec, const gdrhcr::Planner* primary,
                                                    std::vector<int>& group_of) const {
  group_of.resize(exec.cells.size());
  std::iota(group_of.begin(), group_of.end(), 0);
  gd_rhcr_msgs::GroupArray msg;
  if (!primary) return msg;
  const auto groups = primary->groups();
  for (size_t g = 0; g < groups.size(); ++g) {
    gd_rhcr_msgs::Group gm;
    for (int a : groups[g].agents) {
      if (a < 0 || a >= static_cast<int>(exec.robot_of_agent.size())) continue;
      const int r = exec.robot_of_agent[a];  // the planner sees the robots that reported
      gm.members.push_back(r);
      group_of[r] = static_cast<int>(g);
    }
    gm.size = gm.members.size();
    gm.solver = groups[g].solver;
    msg.groups.push_back(gm);
  }
  return msg;
}

// Fallback ticks, deadline misses, planner errors and rejected steps.
void PlannerNode::count_outcome_locked(const TickOutput& exec, uint64_t tick) {
  const DeadlineOutcome& outcome = exec.outcome;
  if (outcome.fallback) {
    ++fallback_ticks_;
    if (outcome.primary_late) {
      ++late_ticks_;
      ROS_WARN_THROTTLE(2.0, "tick %lu: %s missed the %.3f s plan deadline; PIBT moved the fleet",
                        (unsigned long)tick, planner_name_.c_str(), plan_deadline_);
    }
    if (!outcome.primary_error.empty()) {
      ++planner_errors_;
      last_problem_ = "planner failed, PIBT moved the fleet: " + outcome.primary_error;
      last_problem_tick_ = tick_;
      ROS_ERROR_THROTTLE(1.0, "%s", last_problem_.c_str());
    }
  }
  if (!exec.plan_error.empty()) {
    ++invalid_plans_;
    last_problem_ = "planner step rejected, all robots wait: " + exec.plan_error;
    last_problem_tick_ = tick_;
    ROS_ERROR_THROTTLE(1.0, "%s", last_problem_.c_str());
  }
}

// Every robot's command (a robot that never reported gets none), on the fleet topic and, if
// enabled, on its own topic. Between ticks only the robots given a new move are in `command`,
// and the fleet topic is step_command_updates.
void PlannerNode::publish_commands_locked(const std::vector<Cell>& command, uint64_t tick, const ros::Time& stamp,
                                          bool between_ticks) {
  const auto& grid = map_->grid;
  gd_rhcr_msgs::StepCommandArray cmds;
  cmds.header.stamp = stamp;
  cmds.header.frame_id = frame_id_;
  cmds.tick = tick;
  cmds.tick_period = 1.0 / tick_rate_;
  cmds.commands.reserve(command.size());
  for (size_t r = 0; r < command.size(); ++r) {
    if (command[r] == gdrhcr::kNoCell) continue;
    cmds.commands.emplace_back();
    auto& c = cmds.commands.back();
    c.robot_id = r;
    c.tick = tick;
    c.next_x = grid.x_of(command[r]);
    c.next_y = grid.y_of(command[r]);
    c.target_pose = pose_of(command[r]);
    c.mode = operator_->mode(r, fleet_->command_mode(r));
    c.task_id = fleet_->task_of(r);
  }
  if (between_ticks) {
    updates_pub_.publish(cmds);
  } else {
    commands_pub_.publish(cmds);
    tick_freq_->tick();
    tick_stamp_->tick(cmds.header.stamp);
  }
  for (const auto& c : cmds.commands)
    if (c.robot_id < robot_pubs_.size()) robot_pubs_[c.robot_id].publish(c);
}

// The tick's wall time (overruns) and plan-time figures; returns the tick's wall time.
double PlannerNode::record_timing_locked(std::chrono::steady_clock::time_point wall0, uint64_t tick,
                                         const gdrhcr::StepReport& report) {
  const double period = 1.0 / tick_rate_;
  const double step_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double now_s = ros::WallTime::now().toSec();
  tick_stamps_.push_back(now_s);
  while (!tick_stamps_.empty() && tick_stamps_.front() < now_s - 5.0) tick_stamps_.pop_front();
  if (step_time > period) {
    ++overruns_;
    ROS_WARN_THROTTLE(2.0, "tick %lu took %.3f s, longer than the period %.3f s", (unsigned long)tick, step_time, period);
  }
  last_plan_time_ = report.plan_time_s;
  plan_time_sum_ += report.plan_time_s;
  plan_time_max_ = std::max(plan_time_max_, report.plan_time_s);
  step_time_max_ = std::max(step_time_max_, step_time);
  ++plan_time_count_;
  return step_time;
}

void PlannerNode::publish_stats_locked(const TickOutput& exec, const gdrhcr::Planner* primary,
                                       const gd_rhcr_msgs::GroupArray& groups_msg, uint64_t tick,
                                       const ros::Time& stamp, double step_time) {
  const gdrhcr::StepReport& report = exec.outcome.report;
  gd_rhcr_msgs::PlannerStats st;
  st.header.stamp = stamp;
  st.tick = tick;
  st.planner = planner_->primary().name();
  st.num_robots = exec.cells.size();
  st.planned = report.planned;
  st.plan_time = report.plan_time_s;
  st.step_time = step_time;
  st.tick_period = 1.0 / tick_rate_;
  st.overruns = overruns_;
  st.skipped_ticks = skipped_;
  st.forced_waits = exec.held + exec.waiting;
  st.tasks_queued = fleet_->count_in_state(kQueued);
  st.tasks_active = fleet_->count_in_state(kAssigned) + fleet_->count_in_state(kPicked);
  st.tasks_delivered = fleet_->delivered_total();
  st.tasks_failed = fleet_->failed_total();
  st.num_groups = groups_msg.groups.size();
  st.fallback_ticks = fallback_ticks_;
  st.fallback = exec.outcome.fallback;
  st.offline_robots = fleet_->offline_count();
  if (primary) {
    try {
      const auto js = primary->stats();
      st.planner_stats_json = js.dump();
      const PlannerFigures f = planner_figures(js);
      st.solver_calls = f.solver_calls;
      st.solver_failures = f.solver_failures;
      st.solver_timeouts = f.solver_timeouts;
      st.pbs_nodes = f.pbs_nodes;
      st.solver_time_mean = f.solver_time_mean;
      st.groups_replanned_per_step = f.groups_replanned_per_step;
      st.cache_reuses = f.cache_reuses;
      st.threshold_fallbacks = f.threshold_fallbacks;
      st.failure_fallbacks = f.failure_fallbacks;
      st.repairs = f.repairs;
    } catch (const std::exception&) {
    }
  }
  throughput_.add(ros::WallTime::now().toSec(), fleet_->delivered_total());
  st.planner_config = planner_config_string(live_config_);
  st.reconfigures = reconfigures_;
  st.deliveries_per_minute = throughput_.per_minute();
  size_t members = 0;
  for (auto& g : groups_msg.groups) {
    members += g.members.size();
    st.group_size_max = std::max<uint32_t>(st.group_size_max, g.members.size());
  }
  st.group_size_mean = groups_msg.groups.empty() ? 0.0 : double(members) / groups_msg.groups.size();
  st.dispatcher = dispatch_policy_name(dispatcher_->policy());
  st.dispatch_robots = dispatch_stats_.robots;
  st.dispatch_tasks = dispatch_stats_.tasks;
  st.dispatch_assigned = dispatch_stats_.assigned;
  st.dispatch_reassigned = dispatch_stats_.reassigned;
  st.dispatch_reserved = dispatch_stats_.reserved;
  st.dispatch_travel = dispatch_stats_.travel;
  st.dispatch_time = dispatch_stats_.time_s;
  st.paused_robots = operator_->paused_count();
  st.emergency_stop = operator_->emergency_stop();
  stats_pub_.publish(st);
}

void PlannerNode::publish_markers_locked(const std::vector<Cell>& pos, const std::vector<Cell>& next,
                                         const std::vector<std::vector<Cell>>& goals,
                                         const std::vector<int>& group_of,
                                         const std::vector<std::vector<Cell>>& planned_paths) {
  FleetView v;
  v.pos = pos;
  v.next = next;
  v.group_of = group_of;
  v.paths = planned_paths;
  v.goal.resize(pos.size(), gdrhcr::kNoCell);
  v.offline.resize(pos.size());
  v.held.resize(pos.size());
  for (size_t r = 0; r < pos.size(); ++r) {
    if (!goals[r].empty()) v.goal[r] = goals[r][0];
    v.offline[r] = fleet_->robot(r).offline;
    v.held[r] = operator_->paused(static_cast<int>(r));
  }
  v.emergency_stop = operator_->emergency_stop();
  size_t open = 0, queued = 0;
  for (auto& [id, t] : fleet_->tasks()) {
    if (task_finished(t.state)) continue;
    ++open;
    queued += t.state == kQueued;
    if (t.state != kPicked) v.task_pickups.push_back(t.pickup);
    else v.task_deliveries.push_back(t.delivery);
  }
  int groups = 0;
  for (size_t r = 0; r < group_of.size(); ++r) groups = std::max(groups, group_of[r] + 1);
  v.overlay = FleetMarkers::overlay_text(tick_, throughput_.per_minute(), open, queued, groups,
                                         plan_time_count_ ? last_plan_time_ : 0.0, planner_name_,
                                         dispatch_policy_name(dispatcher_->policy()), operator_->summary());
  auto arr = markers_->update(v);
  const ros::Time now = ros::Time::now();
  for (auto& m : arr.markers) m.header.stamp = now;
  if (!arr.markers.empty()) markers_pub_.publish(arr);
}

void PlannerNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& s) {
  std::lock_guard<std::mutex> lock(mutex_);
  HealthCounters c;
  c.overruns = overruns_;
  c.rejected_plans = invalid_plans_;
  c.fallback_ticks = fallback_ticks_;
  c.store_errors = store_errors_;
  c.skipped_ticks = skipped_;
  c.missing_robots = fleet_->missing_robots();
  c.offline_robots = fleet_->offline_count();
  c.paused_robots = operator_->paused_count();
  c.emergency_stop = operator_->emergency_stop();
  const Health h = health_.update(c);
  s.summary(h.level, h.message);
  s.add("planner", planner_name_);
  s.add("planner config", planner_config_string(live_config_));
  s.add("dispatcher", dispatcher_->policy() == DispatchPolicy::kBatch ? "batch" : "greedy");
  s.add("operator", operator_->summary());
  s.add("tick", tick_);
  s.add("tick rate target (Hz)", tick_rate_);
  {
    const double now_s = ros::WallTime::now().toSec();
    double rate = 0;
    if (tick_stamps_.size() >= 2 && now_s - tick_stamps_.front() < 6.0)
      rate = (tick_stamps_.size() - 1) / (tick_stamps_.back() - tick_stamps_.front());
    s.add("tick rate measured (Hz)", rate);
  }
  s.add("plan time mean (s)", plan_time_count_ ? plan_time_sum_ / plan_time_count_ : 0.0);
  s.add("plan time max (s)", plan_time_max_);
  s.add("tick callback max (s)", step_time_max_);
  s.add("overruns", overruns_);
  s.add("plan deadline (s)", plan_deadline_);
  s.add("offline timeout (s)", offline_timeout_);
  s.add("fallback ticks", fallback_ticks_);
  s.add("deadline misses", late_ticks_);
  s.add("planner errors", planner_errors_);
  s.add("offline robots", fleet_->offline_count());
  s.add("paused robots", operator_->paused_count());
  s.add("task store", store_ ? store_->path() : std::string("off"));
  s.add("task store errors", store_errors_);
  s.add("skipped ticks", skipped_);
  s.add("rejected plans", invalid_plans_);
  s.add("ignored robot reports", bad_reports_);
  s.add("execution", execution_ + ", commit horizon " + std::to_string(commit_horizon_) +
                         (dispatch_timer_.isValid() ? ", dispatch on arrival" : ", dispatch at ticks"));
  s.add("moves dispatched between ticks", early_dispatches_);
  // Memory that grows by design up to a bound: the distance rows (dist_budget_mb) and the
  // finished tasks kept for list_tasks (the newest 10000).
  s.add("distance rows cached", dist_->cached_rows());
  s.add("distance cache (MB)", dist_->cached_bytes() / 1048576.0);
  s.add("tasks known", fleet_->tasks().size());
  s.add("tasks delivered", fleet_->delivered_total());
  s.add("tasks failed", fleet_->failed_total());
  s.add("deliveries per minute", throughput_.per_minute());
  s.add("planner reconfigurations", reconfigures_);
  s.add("last problem", last_problem_.empty() ? "none" : last_problem_);
  s.add("last problem at tick", last_problem_tick_);
}

bool PlannerNode::on_set_paused(gd_rhcr_msgs::SetPaused::Request& req, gd_rhcr_msgs::SetPaused::Response& res) {
  std::lock_guard<std::mutex> lock(mutex_);
  const std::string err = operator_->set_paused(req.robot_id, req.paused);
  res.success = err.empty();
  res.message = err.empty() ? operator_->summary() : err;
  if (err.empty())
    ROS_INFO("operator: %s %s; now %s", req.paused ? "pause" : "resume",
             req.robot_id < 0 ? "fleet" : ("robot " + std::to_string(req.robot_id)).c_str(), res.message.c_str());
  else
    ROS_WARN("set_paused refused: %s", err.c_str());
  return true;
}

bool PlannerNode::on_emergency_stop(gd_rhcr_msgs::EmergencyStop::Request& req,
                                    gd_rhcr_msgs::EmergencyStop::Response& res) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    operator_->set_emergency_stop(req.engage);
    res.success = true;
    res.message = operator_->summary();
  }
  if (req.engage) ROS_WARN("operator: EMERGENCY STOP engaged; every robot holds, tasks are kept");
  else ROS_INFO("operator: emergency stop released; now %s", res.message.c_str());
  updater_->force_update();  // diagnose() takes mutex_ itself
  return true;
}

std::string PlannerNode::planner_config_string(const gd_rhcr_planner::PlannerConfig& c) const {
  std::ostringstream o;
  o << "V=" << c.V << " H=" << c.H << " c_soft=" << c.c_soft << " K_threshold=" << c.K_threshold
    << " solver=" << c.solver << " solver2=" << c.solver2;
  if (auto_step_budget_) o << " step_budget=" << step_budget_string(c.plan_deadline);
  return o.str();
}

// The step budget for a plan deadline, in seconds, as a parameter string.
std::string PlannerNode::step_budget_string(double plan_deadline) {
  std::ostringstream o;
  o.precision(6);
  o << kStepBudgetShare * plan_deadline;
  return o.str();
}

gdrhcr::Params PlannerNode::planner_params_for(const gd_rhcr_planner::PlannerConfig& c) const {
  gdrhcr::Params p = base_params_;
  p.set("V", std::to_string(c.V));
  p.set("H", std::to_string(c.H));
  std::ostringstream cs;
  cs.precision(17);
  cs << c.c_soft;
  p.set("c_soft", cs.str());
  if (c.K_threshold > 0) p.set("K_threshold", std::to_string(c.K_threshold));
  p.set("solver", c.solver);
  p.set("solver2", c.solver2);
  if (auto_step_budget_) p.set("step-budget", step_budget_string(c.plan_deadline));
  return p;
}

// dynamic_reconfigure (main thread). Values are checked here; a bad one is put back to the live
// value (the server then shows what runs) and logged. Changes apply at the start of the next tick.
void PlannerNode::on_reconfigure(gd_rhcr_planner::PlannerConfig& c, uint32_t) {
  const double period = 1.0 / tick_rate_;
  std::unique_ptr<gdrhcr::Planner> fresh;
  gd_rhcr_planner::PlannerConfig live;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    live = config_pending_ ? pending_config_ : live_config_;
  }
  if (c.plan_deadline == 0) c.plan_deadline = 0.7 * period;
  if (!(c.plan_deadline > 0 && c.plan_deadline <= period)) {
    ROS_ERROR("reconfigure: plan_deadline %.3f s is outside (0, 1/tick_rate = %.3f s]; keeping %.3f s",
              c.plan_deadline, period, live.plan_deadline);
    c.plan_deadline = live.plan_deadline;
  }
  try {
    parse_dispatch_policy(c.dispatcher);
  } catch (const std::exception& e) {
    ROS_ERROR("reconfigure: %s; keeping %s", e.what(), live.dispatcher.c_str());
    c.dispatcher = live.dispatcher;
  }
  if (planner_config_string(c) != planner_config_string(live)) {
    try {
      gdrhcr::Params p = planner_params_for(c);
      fresh = gdrhcr::make_planner(planner_name_, p, map_->grid, num_robots_, seed_);
    } catch (const std::exception& e) {
      ROS_ERROR("reconfigure: planner parameters rejected (%s); keeping %s", e.what(),
                planner_config_string(live).c_str());
      c.V = live.V, c.H = live.H, c.c_soft = live.c_soft, c.K_threshold = live.K_threshold;
      c.solver = live.solver, c.solver2 = live.solver2;
    }
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (fresh) pending_planner_ = std::move(fresh);
  pending_config_ = c;
  config_pending_ = true;
}

// At the start of a tick, with mutex_ held: the planner built by on_reconfigure replaces the
// running one (tasks stay in the Fleet; the new planner plans from the robots' cells). The old
// one is handed back to be destroyed outside the lock (it may wait for an abandoned step).
void PlannerNode::apply_reconfigure_locked(std::unique_ptr<DeadlinePlanner>& retired) {
  if (!config_pending_) return;
  config_pending_ = false;
  const auto& c = pending_config_;
  if (pending_planner_) {
    gdrhcr::Params no_params;
    retired = std::move(planner_);
    planner_ = std::make_unique<DeadlinePlanner>(
        std::move(pending_planner_), gdrhcr::make_planner("pibt", no_params, map_->grid, num_robots_, seed_));
    ++reconfigures_;
    ROS_INFO("reconfigure: planner %s now runs with %s (tick %lu)", planner_name_.c_str(),
             planner_config_string(c).c_str(), (unsigned long)tick_);
  }
  plan_deadline_ = c.plan_deadline;
  offline_timeout_ = c.offline_timeout;
  DispatchParams dp = dispatcher_->params();
  dp.switch_margin = c.dispatch_switch_margin;
  dp.finish_horizon = c.dispatch_finish_horizon;
  if (c.dispatcher != dispatch_policy_name(dispatcher_->policy()) || dp.switch_margin != dispatcher_->params().switch_margin ||
      dp.finish_horizon != dispatcher_->params().finish_horizon)
    dispatcher_ = std::make_unique<Dispatcher>(parse_dispatch_policy(c.dispatcher), dp);
  live_config_ = c;
}

}  // namespace
}  // namespace gd_rhcr_planner

int main(int argc, char** argv) {
  ros::init(argc, argv, "gd_rhcr_planner");
  ros::NodeHandle nh, pnh("~");
  // Declared before the node so it outlives the node: the tick timer lives on this queue.
  ros::CallbackQueue tick_queue;
  gd_rhcr_planner::PlannerNode node(nh, pnh);
  try {
    node.init();
  } catch (const std::exception& e) {
    ROS_FATAL("gd_rhcr_planner: %s", e.what());
    return 1;
  }
  // Ticks run on their own queue and thread, so a long planning step never blocks services,
  // state updates or the action server (handled by the main thread).
  node.start_timers(&tick_queue);
  ros::AsyncSpinner tick_spinner(1, &tick_queue);
  tick_spinner.start();
  ros::spin();
  tick_spinner.stop();
  return 0;
}
