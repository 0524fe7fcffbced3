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
#include <nav_msgs/OccupancyGrid.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <gd_rhcr_msgs/CancelTask.h>
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
#include "gd_rhcr_planner/execution.hpp"
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

// A colour per index, spread around the hue circle (golden ratio steps).
std_msgs::ColorRGBA palette(int i, float alpha = 1.0f) {
  const double h = std::fmod(i * 0.618033988749895, 1.0) * 6.0;
  const double s = 0.75, v = 0.95;
  const int k = static_cast<int>(h);
  const double f = h - k, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r, g, b;
  switch (k % 6) {
    case 0: r = v, g = t, b = p; break;
    case 1: r = q, g = v, b = p; break;
    case 2: r = p, g = v, b = t; break;
    case 3: r = p, g = q, b = v; break;
    case 4: r = t, g = p, b = v; break;
    default: r = v, g = p, b = q; break;
  }
  std_msgs::ColorRGBA c;
  c.r = r, c.g = g, c.b = b, c.a = alpha;
  return c;
}

std_msgs::ColorRGBA rgba(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r, c.g = g, c.b = b, c.a = a;
  return c;
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
  void on_diagnostics(const ros::TimerEvent&);

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
  bool per_robot_topics_ = false, publish_markers_ = true;
  gdrhcr::Params planner_params_;

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
  // Issue 13: the execution layer (ADG or lock-step), used by the tick thread only.
  std::string execution_ = "adg";
  int commit_horizon_ = 1;
  std::unique_ptr<Executor> executor_;
  double first_report_s_ = 0;  // when the first robot reported (missing robots are waited for a while)
  std::deque<double> tick_stamps_;  // wall times of recent published ticks, for the rate
  double plan_time_sum_ = 0, plan_time_max_ = 0, step_time_max_ = 0;
  int plan_time_count_ = 0;
  std::string last_problem_;  // the latest problem, kept after it is over (see its tick)
  uint64_t last_problem_tick_ = 0;

  ros::Publisher commands_pub_, status_pub_, map_pub_, mapd_pub_, markers_pub_, stats_pub_,
      groups_pub_, diag_pub_;
  std::vector<ros::Publisher> robot_pubs_;
  ros::Subscriber states_sub_, tasks_sub_;
  ros::ServiceServer submit_srv_, cancel_srv_, list_srv_;
  std::unique_ptr<DeliveryServer> action_;
  ros::Timer tick_timer_, diag_timer_;
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
  pnh_.param("execution", execution_, std::string("adg"));    // issue 13: adg | lockstep
  pnh_.param("commit_horizon", commit_horizon_, 1);
  if (!pnh_.getParam("task_store", task_store_path_) || task_store_path_ == "default")
    task_store_path_ = default_task_store();
  if (task_store_path_ == "none") task_store_path_.clear();
  if (!(tick_rate_ > 0 && tick_rate_ <= 1000)) throw gdrhcr::ParamError("~tick_rate must be in (0, 1000] Hz");
  if (plan_deadline_ == 0) plan_deadline_ = 0.7 / tick_rate_;
  if (!(plan_deadline_ > 0 && plan_deadline_ <= 1.0 / tick_rate_))
    throw gdrhcr::ParamError("~plan_deadline must be in (0, 1/tick_rate] seconds (0 = 0.7/tick_rate)");
  if (!(offline_timeout_ > 0)) throw gdrhcr::ParamError("~offline_timeout must be > 0 seconds");
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
  }
  XmlRpc::XmlRpcValue extra;
  if (pnh_.getParam("planner_params", extra) && extra.getType() == XmlRpc::XmlRpcValue::TypeStruct) {
    for (auto it = extra.begin(); it != extra.end(); ++it) planner_params_.set(it->first, xmlrpc_to_string(it->second));
  }
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
    ExecutorConfig ec;
    ec.mode = parse_execution_mode(execution_);
    ec.commit_horizon = commit_horizon_;
    ec.plan_deadline_s = plan_deadline_;
    ec.dist_budget_bytes = size_t(dist_budget_mb_) << 20;
    executor_ = std::make_unique<Executor>(grid, *dist_, num_robots_, ec);
  }
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
  status_pub_ = nh_.advertise<gd_rhcr_msgs::TaskStatus>("task_status", 1000);
  map_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
  mapd_pub_ = nh_.advertise<gd_rhcr_msgs::MapdCells>("mapd_cells", 1, true);
  markers_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("fleet_markers", 1, true);
  stats_pub_ = nh_.advertise<gd_rhcr_msgs::PlannerStats>("planner_stats", 10);
  groups_pub_ = nh_.advertise<gd_rhcr_msgs::GroupArray>("planner_groups", 10);
  diag_pub_ = nh_.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
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
  diag_timer_ = nh_.createTimer(ros::Duration(1.0), &PlannerNode::on_diagnostics, this);
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

void PlannerNode::on_tick(const ros::TimerEvent& ev) {
  const auto wall0 = std::chrono::steady_clock::now();
  const double period = 1.0 / tick_rate_;
  std::vector<Cell> pos, next;
  std::vector<std::vector<Cell>> goals;
  std::vector<RobotRecord> robots;
  bool proceed_without_missing = false;
  uint64_t tick;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    tick = ++tick_;
    for (int r : fleet_->mark_silent(ros::Time::now().toSec(), offline_timeout_))
      ROS_WARN("robot %d sent no state for %.1f s: offline (an obstacle at its last cell); its task is requeued",
               r, offline_timeout_);
    // Robots that never reported are waited for ~offline_timeout after the first report, then
    // left out (taken to be off the floor); the rest of the fleet moves (issue 13).
    const double now_s = ros::Time::now().toSec();
    const int missing = fleet_->missing_robots();
    if (missing < fleet_->num_robots() && first_report_s_ == 0) first_report_s_ = now_s;
    proceed_without_missing = first_report_s_ > 0 && now_s - first_report_s_ >= offline_timeout_;
    if (missing > 0 && proceed_without_missing) {
      last_problem_ = std::to_string(missing) + " robots never reported a state: left out of planning";
      last_problem_tick_ = tick_;
      ROS_WARN_THROTTLE(10.0, "%s", last_problem_.c_str());
    }
    fleet_->advance();
    publish_events_locked();
    fleet_->fill_positions(pos);
    fleet_->fill_goals(goals);
    robots.reserve(pos.size());
    for (int r = 0; r < fleet_->num_robots(); ++r) robots.push_back(fleet_->robot(r));
  }

  // Liveness, planning, reservation, commitment and validation: the execution layer (ADG or
  // lock-step, execution.hpp), outside the lock, so services and state updates keep flowing.
  const auto& grid = map_->grid;
  executor_->set_plan_deadline(plan_deadline_);
  TickOutput exec = executor_->tick(robots, goals, *planner_, proceed_without_missing);
  if (!exec.stepped) {
    std::lock_guard<std::mutex> lock(mutex_);
    ++skipped_;
    last_problem_ = exec.skip_reason;
    last_problem_tick_ = tick_;
    ROS_INFO_THROTTLE(5.0, "no step: %s", last_problem_.c_str());
    return;
  }
  for (const std::string& w : exec.warnings) ROS_WARN("%s", w.c_str());
  pos = exec.cells;
  next = exec.command;
  const DeadlineOutcome& outcome = exec.outcome;
  const gdrhcr::StepReport& report = outcome.report;
  const int held_count = exec.held + exec.waiting;
  const std::string plan_error = exec.plan_error;

  // The primary planner's groups and paths, when it planned this tick (else it may still be
  // running an abandoned step on its worker and must not be read).
  const gdrhcr::Planner* primary = outcome.fallback ? nullptr : &planner_->primary();
  std::vector<int> group_of(pos.size());
  std::iota(group_of.begin(), group_of.end(), 0);
  gd_rhcr_msgs::GroupArray groups_msg;
  if (primary) {
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
      groups_msg.groups.push_back(gm);
    }
  }
  std::vector<std::vector<Cell>> planned;
  if (primary && publish_markers_) {
    planned.resize(pos.size());
    for (size_t a = 0; a < exec.robot_of_agent.size(); ++a)
      planned[exec.robot_of_agent[a]] = primary->planned_path(static_cast<int>(a));
  }

  gd_rhcr_msgs::StepCommandArray cmds;
  cmds.header.stamp = ev.current_real.isZero() ? ros::Time::now() : ev.current_real;
  cmds.header.frame_id = frame_id_;
  cmds.tick = tick;
  cmds.tick_period = period;
  std::lock_guard<std::mutex> lock(mutex_);
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
  if (!plan_error.empty()) {
    ++invalid_plans_;
    last_problem_ = "planner step rejected, all robots wait: " + plan_error;
    last_problem_tick_ = tick_;
    ROS_ERROR_THROTTLE(1.0, "%s", last_problem_.c_str());
  }
  cmds.commands.reserve(pos.size());
  for (size_t r = 0; r < pos.size(); ++r) {
    if (next[r] == gdrhcr::kNoCell) continue;  // a robot that never reported gets no command
    cmds.commands.emplace_back();
    auto& c = cmds.commands.back();
    c.robot_id = r;
    c.tick = tick;
    c.next_x = grid.x_of(next[r]);
    c.next_y = grid.y_of(next[r]);
    c.target_pose = pose_of(next[r]);
    c.mode = fleet_->mode(r);
    c.task_id = fleet_->task_of(r);
  }
  commands_pub_.publish(cmds);
  for (const auto& c : cmds.commands)
    if (c.robot_id < robot_pubs_.size()) robot_pubs_[c.robot_id].publish(c);

  const double step_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  const double now_s = ros::WallTime::now().toSec();
  tick_stamps_.push_back(now_s);
  while (!tick_stamps_.empty() && tick_stamps_.front() < now_s - 5.0) tick_stamps_.pop_front();
  if (step_time > period) {
    ++overruns_;
    ROS_WARN_THROTTLE(2.0, "tick %lu took %.3f s, longer than the period %.3f s", (unsigned long)tick, step_time, period);
  }
  plan_time_sum_ += report.plan_time_s;
  plan_time_max_ = std::max(plan_time_max_, report.plan_time_s);
  step_time_max_ = std::max(step_time_max_, step_time);
  ++plan_time_count_;

  gd_rhcr_msgs::PlannerStats st;
  st.header.stamp = cmds.header.stamp;
  st.tick = tick;
  st.planner = planner_->primary().name();
  st.num_robots = pos.size();
  st.planned = report.planned;
  st.plan_time = report.plan_time_s;
  st.step_time = step_time;
  st.tick_period = period;
  st.overruns = overruns_;
  st.skipped_ticks = skipped_;
  st.forced_waits = held_count;
  st.tasks_queued = fleet_->count_in_state(kQueued);
  st.tasks_active = fleet_->count_in_state(kAssigned) + fleet_->count_in_state(kPicked);
  st.tasks_delivered = fleet_->delivered_total();
  st.tasks_failed = fleet_->failed_total();
  st.num_groups = groups_msg.groups.size();
  st.fallback_ticks = fallback_ticks_;
  st.fallback = outcome.fallback;
  st.offline_robots = fleet_->offline_count();
  if (primary) {
    try {
      st.planner_stats_json = primary->stats().dump();
    } catch (const std::exception&) {
    }
  }
  stats_pub_.publish(st);
  if (!groups_msg.groups.empty()) {
    groups_msg.header = cmds.header;
    groups_msg.tick = tick;
    groups_pub_.publish(groups_msg);
  }
  if (publish_markers_) publish_markers_locked(pos, next, goals, group_of, planned);
}

void PlannerNode::publish_markers_locked(const std::vector<Cell>& pos, const std::vector<Cell>& next,
                                         const std::vector<std::vector<Cell>>& goals,
                                         const std::vector<int>& group_of,
                                         const std::vector<std::vector<Cell>>& planned_paths) {
  const double res = map_->frame.resolution;
  visualization_msgs::MarkerArray arr;
  auto base = [&](const std::string& ns, int type) {
    visualization_msgs::Marker m;
    m.header.frame_id = frame_id_;
    m.header.stamp = ros::Time::now();
    m.ns = ns;
    m.id = 0;
    m.type = type;
    m.action = visualization_msgs::Marker::ADD;
    m.pose.orientation.w = 1.0;
    m.frame_locked = false;
    return m;
  };
  // Robots, one colour per group (one group per robot when the planner reports none).
  auto robots = base("robots", visualization_msgs::Marker::SPHERE_LIST);
  robots.scale.x = robots.scale.y = robots.scale.z = 0.8 * res;
  // Next cells (the planned step) as line segments, goals as small cubes.
  auto steps = base("planned_steps", visualization_msgs::Marker::LINE_LIST);
  steps.scale.x = 0.15 * res;
  steps.color = rgba(1, 1, 1, 0.9);
  auto goal_m = base("goals", visualization_msgs::Marker::CUBE_LIST);
  goal_m.scale.x = goal_m.scale.y = 0.35 * res;
  goal_m.scale.z = 0.1 * res;
  auto paths = base("goal_lines", visualization_msgs::Marker::LINE_LIST);
  paths.scale.x = 0.05 * res;
  for (size_t r = 0; r < pos.size(); ++r) {
    const auto colour = palette(group_of[r]);
    robots.points.push_back(point_of(pos[r], 0.4 * res));
    robots.colors.push_back(fleet_->robot(r).offline ? rgba(0.3, 0.3, 0.3, 1) : colour);
    if (next[r] != pos[r]) {
      steps.points.push_back(point_of(pos[r], 0.45 * res));
      steps.points.push_back(point_of(next[r], 0.45 * res));
    }
    if (!goals[r].empty() && goals[r][0] != pos[r]) {
      goal_m.points.push_back(point_of(goals[r][0], 0.05 * res));
      goal_m.colors.push_back(colour);
      paths.points.push_back(point_of(pos[r], 0.3 * res));
      paths.points.push_back(point_of(goals[r][0], 0.05 * res));
      auto faint = colour;
      faint.a = 0.35;
      paths.colors.push_back(faint);
      paths.colors.push_back(faint);
    }
  }
  arr.markers.push_back(robots);
  arr.markers.push_back(steps);
  arr.markers.push_back(goal_m);
  arr.markers.push_back(paths);
  {  // the planner's paths (GD-RHCR, RHCR); kept empty on fallback ticks and for PIBT
    auto planned = base("planned_paths", visualization_msgs::Marker::LINE_LIST);
    planned.scale.x = 0.08 * res;
    for (size_t r = 0; r < planned_paths.size(); ++r) {
      const auto& path = planned_paths[r];
      auto colour = palette(group_of[r], 0.7f);
      for (size_t t = 1; t < path.size(); ++t) {
        if (path[t] == path[t - 1]) continue;
        planned.points.push_back(point_of(path[t - 1], 0.2 * res));
        planned.points.push_back(point_of(path[t], 0.2 * res));
        planned.colors.push_back(colour);
        planned.colors.push_back(colour);
      }
    }
    arr.markers.push_back(planned);
  }
  // Pickup (orange) and delivery (green) cells of the open tasks.
  auto pick = base("pickups", visualization_msgs::Marker::CUBE_LIST);
  pick.scale.x = pick.scale.y = 0.9 * res;
  pick.scale.z = 0.02 * res;
  pick.color = rgba(1.0, 0.55, 0.0, 0.6);
  auto drop = pick;
  drop.ns = "deliveries";
  drop.color = rgba(0.1, 0.8, 0.2, 0.6);
  for (auto& [id, t] : fleet_->tasks()) {
    if (task_finished(t.state)) continue;
    if (t.state != kPicked) pick.points.push_back(point_of(t.pickup, 0.01 * res));
    drop.points.push_back(point_of(t.delivery, 0.01 * res));
  }
  arr.markers.push_back(pick);
  arr.markers.push_back(drop);
  // Labels for small fleets.
  if (static_cast<int>(pos.size()) <= label_limit_) {
    for (size_t r = 0; r < pos.size(); ++r) {
      auto label = base("labels", visualization_msgs::Marker::TEXT_VIEW_FACING);
      label.id = static_cast<int>(r);
      label.pose.position = point_of(pos[r], 1.1 * res);
      label.scale.z = 0.6 * res;
      label.color = rgba(1, 1, 1, 1);
      label.text = std::to_string(r);
      arr.markers.push_back(label);
    }
  }
  // Empty point lists are invalid for rviz; drop those markers by DELETE.
  for (auto& m : arr.markers)
    if ((m.type == visualization_msgs::Marker::LINE_LIST || m.type == visualization_msgs::Marker::CUBE_LIST ||
         m.type == visualization_msgs::Marker::SPHERE_LIST) && m.points.empty())
      m.action = visualization_msgs::Marker::DELETE;
  markers_pub_.publish(arr);
}

void PlannerNode::on_diagnostics(const ros::TimerEvent&) {
  std::lock_guard<std::mutex> lock(mutex_);
  diagnostic_msgs::DiagnosticArray arr;
  arr.header.stamp = ros::Time::now();
  diagnostic_msgs::DiagnosticStatus s;
  s.name = ros::this_node::getName() + ": planner";
  s.hardware_id = "gd_rhcr_fleet";
  const double now_s = ros::WallTime::now().toSec();
  double rate = 0;
  if (tick_stamps_.size() >= 2 && now_s - tick_stamps_.front() < 6.0)
    rate = (tick_stamps_.size() - 1) / (tick_stamps_.back() - tick_stamps_.front());
  static uint64_t last_overruns = 0, last_invalid = 0, last_fallbacks = 0;
  const bool new_overruns = overruns_ > last_overruns, new_invalid = invalid_plans_ > last_invalid;
  const bool new_fallbacks = fallback_ticks_ > last_fallbacks;
  last_overruns = overruns_, last_invalid = invalid_plans_, last_fallbacks = fallback_ticks_;
  if (!fleet_->all_reported()) {
    s.level = diagnostic_msgs::DiagnosticStatus::WARN;
    s.message = std::to_string(fleet_->missing_robots()) + " robots not reporting";
  } else if (new_invalid) {
    s.level = diagnostic_msgs::DiagnosticStatus::ERROR;
    s.message = "planner step rejected; robots held";
  } else if (store_ && store_errors_ > 0) {
    s.level = diagnostic_msgs::DiagnosticStatus::ERROR;
    s.message = "task store write failed";
  } else if (new_overruns) {
    s.level = diagnostic_msgs::DiagnosticStatus::WARN;
    s.message = "tick overruns";
  } else if (new_fallbacks) {
    s.level = diagnostic_msgs::DiagnosticStatus::WARN;
    s.message = "planner missed its deadline; PIBT fallback ticks";
  } else {
    s.level = diagnostic_msgs::DiagnosticStatus::OK;
    s.message = "planning";
  }
  auto kv = [&](const std::string& k, const std::string& v) {
    diagnostic_msgs::KeyValue x;
    x.key = k;
    x.value = v;
    s.values.push_back(x);
  };
  kv("planner", planner_name_);
  kv("tick", std::to_string(tick_));
  kv("tick rate target (Hz)", std::to_string(tick_rate_));
  kv("tick rate measured (Hz)", std::to_string(rate));
  kv("plan time mean (s)", std::to_string(plan_time_count_ ? plan_time_sum_ / plan_time_count_ : 0.0));
  kv("plan time max (s)", std::to_string(plan_time_max_));
  kv("tick callback max (s)", std::to_string(step_time_max_));
  kv("overruns", std::to_string(overruns_));
  kv("plan deadline (s)", std::to_string(plan_deadline_));
  kv("fallback ticks", std::to_string(fallback_ticks_));
  kv("deadline misses", std::to_string(late_ticks_));
  kv("planner errors", std::to_string(planner_errors_));
  kv("offline robots", std::to_string(fleet_->offline_count()));
  kv("task store", store_ ? store_->path() : std::string("off"));
  kv("task store errors", std::to_string(store_errors_));
  kv("skipped ticks", std::to_string(skipped_));
  kv("rejected plans", std::to_string(invalid_plans_));
  kv("ignored robot reports", std::to_string(bad_reports_));
  // Memory that grows by design up to a bound: the distance rows (dist_budget_mb) and the
  // finished tasks kept for list_tasks (the newest 10000).
  kv("distance rows cached", std::to_string(dist_->cached_rows()));
  kv("distance cache (MB)", std::to_string(dist_->cached_bytes() / 1048576.0));
  kv("tasks known", std::to_string(fleet_->tasks().size()));
  kv("tasks delivered", std::to_string(fleet_->delivered_total()));
  kv("tasks failed", std::to_string(fleet_->failed_total()));
  kv("last problem", last_problem_.empty() ? "none" : last_problem_);
  kv("last problem at tick", std::to_string(last_problem_tick_));
  arr.status.push_back(s);
  diag_pub_.publish(arr);
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
