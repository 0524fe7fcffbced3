// gd_rhcr_planner_node: the ROS face of the fleet manager (fleet_manager.hpp). It reads the
// private parameters into a FleetConfig, converts messages to and from the manager's plain
// structs, and wires topics, services, the Delivery action, timers, dynamic_reconfigure and
// diagnostics. Topics, services and parameters: gd_rhcr_planner/README.md.
#include <algorithm>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>

#include <actionlib/server/action_server.h>
#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <dynamic_reconfigure/server.h>
#include <nav_msgs/OccupancyGrid.h>
#include <ros/callback_queue.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include <gd_rhcr_msgs/CancelTask.h>
#include <gd_rhcr_msgs/DeliveryAction.h>
#include <gd_rhcr_msgs/EmergencyStop.h>
#include <gd_rhcr_msgs/GroupArray.h>
#include <gd_rhcr_msgs/ListTasks.h>
#include <gd_rhcr_msgs/MapdCells.h>
#include <gd_rhcr_msgs/PlannerStats.h>
#include <gd_rhcr_msgs/RobotStateArray.h>
#include <gd_rhcr_msgs/SetPaused.h>
#include <gd_rhcr_msgs/StepCommandArray.h>
#include <gd_rhcr_msgs/SubmitTask.h>
#include <gd_rhcr_msgs/Task.h>
#include <gd_rhcr_msgs/TaskStatus.h>
#include <gd_rhcr_planner/PlannerConfig.h>

#include "gd_rhcr_planner/fleet_manager.hpp"
#include "gd_rhcr_planner/fleet_markers.hpp"
#include "gd_rhcr_planner/map_loader.hpp"
#include "gd_rhcr_planner/ros_messages.hpp"
#include "gdrhcr/task_stream.hpp"

namespace gd_rhcr_planner {
namespace {

using DeliveryServer = actionlib::ActionServer<gd_rhcr_msgs::DeliveryAction>;

class PlannerNode {
 public:
  PlannerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh), pnh_(pnh) {}
  // Throws on a bad map or parameter (the node then exits with the message).
  void init();
  void start_timers(ros::CallbackQueue* tick_queue);

 private:
  FleetConfig load_config();
  void read_planner_params(FleetConfig& cfg);
  void advertise();
  void publish_static(const gdrhcr::MapdCells& mapd);
  void on_states(const gd_rhcr_msgs::RobotStateArray::ConstPtr& msg);
  void on_task(const gd_rhcr_msgs::Task::ConstPtr& msg);
  bool on_submit(gd_rhcr_msgs::SubmitTask::Request& req, gd_rhcr_msgs::SubmitTask::Response& res);
  bool on_cancel(gd_rhcr_msgs::CancelTask::Request& req, gd_rhcr_msgs::CancelTask::Response& res);
  bool on_list(gd_rhcr_msgs::ListTasks::Request& req, gd_rhcr_msgs::ListTasks::Response& res);
  void on_goal(DeliveryServer::GoalHandle gh);
  void on_cancel_goal(DeliveryServer::GoalHandle gh);
  bool on_set_paused(gd_rhcr_msgs::SetPaused::Request& req, gd_rhcr_msgs::SetPaused::Response& res);
  bool on_emergency_stop(gd_rhcr_msgs::EmergencyStop::Request& req, gd_rhcr_msgs::EmergencyStop::Response& res);
  void on_reconfigure(PlannerConfig& config, uint32_t level);
  void on_tick(const ros::TimerEvent& ev);
  void on_dispatch(const ros::TimerEvent& ev);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& stat);
  void publish_events();
  void publish_commands(const std::vector<RobotCommand>& commands, uint64_t tick, const ros::Time& stamp,
                        bool between_ticks);

  ros::NodeHandle nh_, pnh_;
  std::string map_path_, frame_id_;
  double cell_size_ = 1.0;
  int label_limit_ = 60;
  bool per_robot_topics_ = false, publish_markers_ = true, show_goal_lines_ = false;
  std::unique_ptr<LoadedMap> map_;
  std::unique_ptr<FleetManager> fleet_;
  std::mutex markers_mutex_;  // markers_ (tick thread and new subscribers)
  std::unique_ptr<FleetMarkers> markers_;
  std::mutex events_mutex_;   // task events in order, and goal_of_task_
  std::map<uint64_t, DeliveryServer::GoalHandle> goal_of_task_;

  ros::Publisher commands_pub_, updates_pub_, status_pub_, map_pub_, mapd_pub_, markers_pub_, stats_pub_, groups_pub_;
  std::vector<ros::Publisher> robot_pubs_;
  ros::Subscriber states_sub_, tasks_sub_;
  ros::ServiceServer submit_srv_, cancel_srv_, list_srv_, pause_srv_, estop_srv_;
  std::unique_ptr<DeliveryServer> action_;
  ros::Timer tick_timer_, diag_timer_, dispatch_timer_;
  std::unique_ptr<diagnostic_updater::Updater> updater_;
  double tick_freq_min_ = 0, tick_freq_max_ = 0;
  std::unique_ptr<diagnostic_updater::FrequencyStatus> tick_freq_;
  std::unique_ptr<diagnostic_updater::TimeStampStatus> tick_stamp_;
  std::unique_ptr<dynamic_reconfigure::Server<PlannerConfig>> reconfigure_;
  boost::recursive_mutex reconfigure_mutex_;
};

// The private parameters: the node's own, then the planner's (checked against its table; names
// of other planners are ignored, anything else is an error naming it).
FleetConfig PlannerNode::load_config() {
  FleetConfig c;
  if (!pnh_.getParam("map", map_path_) || map_path_.empty())
    throw gdrhcr::ParamError("parameter ~map (path of a .map, kiva .map or map_server .yaml) is required");
  pnh_.param("planner", c.planner, std::string("gd-rhcr"));
  pnh_.param("action_model", c.action_model, c.action_model);
  pnh_.param("frame_id", frame_id_, std::string("map"));
  pnh_.param("cell_size", cell_size_, 1.0);
  pnh_.param("tick_rate", c.tick_rate, c.tick_rate);
  pnh_.param("num_robots", c.num_robots, c.num_robots);
  int seed = 1;
  pnh_.param("seed", seed, 1);
  c.seed = static_cast<uint64_t>(seed);
  pnh_.param("per_robot_topics", per_robot_topics_, false);
  pnh_.param("publish_markers", publish_markers_, true);
  pnh_.param("label_limit", label_limit_, 60);
  pnh_.param("show_goal_lines", show_goal_lines_, false);
  pnh_.param("dist_budget_mb", c.dist_budget_mb, c.dist_budget_mb);
  pnh_.param("prep_file", c.prep_file, c.prep_file);
  pnh_.param("plan_deadline", c.plan_deadline, 0.0);
  pnh_.param("offline_timeout", c.offline_timeout, c.offline_timeout);
  pnh_.param("commit_horizon", c.commit_horizon, c.commit_horizon);
  pnh_.param("catch_up", c.catch_up, c.catch_up);
  pnh_.param("dispatch_rate", c.dispatch_rate, c.dispatch_rate);
  pnh_.param("dispatcher", c.dispatcher, c.dispatcher);
  pnh_.param("dispatch_finish_horizon", c.dispatch.finish_horizon, c.dispatch.finish_horizon);
  pnh_.param("dispatch_switch_margin", c.dispatch.switch_margin, c.dispatch.switch_margin);
  pnh_.param("dispatch_max_tasks", c.dispatch.max_tasks, c.dispatch.max_tasks);
  pnh_.param("dispatch_age_weight", c.dispatch.age_weight, c.dispatch.age_weight);
  if (!pnh_.getParam("task_store", c.task_store) || c.task_store == "default") c.task_store = default_task_store(ros::this_node::getName());
  if (c.task_store == "none") c.task_store.clear();
  if (!(cell_size_ > 0)) throw gdrhcr::ParamError("~cell_size must be > 0 metres");
  c.validate();
  read_planner_params(c);
  return c;
}

void PlannerNode::read_planner_params(FleetConfig& cfg) {
  std::vector<std::string> names;
  ros::param::getParamNames(names);
  const std::string prefix = pnh_.getNamespace() + "/";
  for (const std::string& full : names) {
    if (full.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string name = full.substr(prefix.size());
    if (name.find('/') != std::string::npos) continue;  // planner_params/..., read below
    if (classify_node_param(name, cfg.planner) != NodeParamKind::kPlanner) continue;
    XmlRpc::XmlRpcValue v;
    pnh_.getParam(name, v);
    // K_threshold 0 is dynamic_reconfigure's "the planner's rule".
    if (name == "K_threshold" && v.getType() == XmlRpc::XmlRpcValue::TypeInt && static_cast<int>(v) == 0) continue;
    cfg.planner_params.set(name, xmlrpc_to_string(v, name));
  }
  XmlRpc::XmlRpcValue extra;
  if (!pnh_.getParam("planner_params", extra)) return;
  if (extra.getType() != XmlRpc::XmlRpcValue::TypeStruct)
    throw gdrhcr::ParamError("~planner_params must be a dictionary of the planner's parameters");
  for (auto it = extra.begin(); it != extra.end(); ++it)  // every one must be the planner's
    cfg.planner_params.set(it->first, xmlrpc_to_string(it->second, "planner_params/" + it->first));
}

void PlannerNode::init() {
  FleetConfig cfg = load_config();
  map_ = std::make_unique<LoadedMap>(load_map(map_path_, cell_size_));
  const auto& grid = map_->grid;
  fleet_ = std::make_unique<FleetManager>(grid, cfg, ros_log);
  const gdrhcr::MapdCells mapd = map_->format == "map_server" ? gdrhcr::default_mapd_cells(grid)
                                                              : gdrhcr::mapd_cells_for_map(grid, map_path_);
  ROS_INFO("map %s (%s, %dx%d, %zu free cells, %.3f m/cell); planner %s (%s); %d robots; tick %.2f Hz",
           map_path_.c_str(), map_->format.c_str(), grid.width(), grid.height(), grid.free_cells().size(),
           map_->frame.resolution, cfg.planner.c_str(), fleet_->planner_config_string().c_str(), cfg.num_robots,
           cfg.tick_rate);
  std::vector<gdrhcr::Cell> stations = mapd.pickups;
  stations.insert(stations.end(), mapd.deliveries.begin(), mapd.deliveries.end());
  const double t0 = ros::WallTime::now().toSec();
  const size_t rows = fleet_->prepare_distances(stations);
  ROS_INFO("distances to the %zu pickup and delivery cells computed in %.2f s (%zu rows cached)", stations.size(),
           ros::WallTime::now().toSec() - t0, rows);
  MarkerStyle style;
  style.frame_id = frame_id_;
  style.label_limit = label_limit_;
  style.show_goal_lines = show_goal_lines_;
  markers_ = std::make_unique<FleetMarkers>(grid, map_->frame, style);
  markers_->set_stations(mapd.pickups, mapd.deliveries);
  advertise();
  publish_static(mapd);
}

void PlannerNode::advertise() {
  const FleetConfig& cfg = fleet_->config();
  commands_pub_ = nh_.advertise<gd_rhcr_msgs::StepCommandArray>("step_commands", 10);
  // Between ticks: the commands of the robots just given a move, nobody else's.
  updates_pub_ = nh_.advertise<gd_rhcr_msgs::StepCommandArray>("step_command_updates", 100);
  status_pub_ = nh_.advertise<gd_rhcr_msgs::TaskStatus>("task_status", 1000);
  map_pub_ = nh_.advertise<nav_msgs::OccupancyGrid>("map", 1, true);
  mapd_pub_ = nh_.advertise<gd_rhcr_msgs::MapdCells>("mapd_cells", 1, true);
  stats_pub_ = nh_.advertise<gd_rhcr_msgs::PlannerStats>("planner_stats", 10);
  groups_pub_ = nh_.advertise<gd_rhcr_msgs::GroupArray>("planner_groups", 10);
  // Markers are sent as changes; a new subscriber first gets the whole picture.
  markers_pub_ = nh_.advertise<visualization_msgs::MarkerArray>(
      "fleet_markers", 1, [this](const ros::SingleSubscriberPublisher& sub) {
        std::lock_guard<std::mutex> lock(markers_mutex_);
        if (markers_->current().empty()) return;
        visualization_msgs::MarkerArray all;
        all.markers = markers_->current();
        sub.publish(all);
      }, ros::SubscriberStatusCallback(), ros::VoidConstPtr(), false);
  updater_ = std::make_unique<diagnostic_updater::Updater>();
  updater_->setHardwareID("gd_rhcr_fleet" + nh_.getNamespace());
  updater_->add("planner", this, &PlannerNode::diagnose);
  tick_freq_min_ = 0.9 * cfg.tick_rate;
  tick_freq_max_ = 1.1 * cfg.tick_rate;
  tick_freq_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      diagnostic_updater::FrequencyStatusParam(&tick_freq_min_, &tick_freq_max_, 0.05, 10), "tick rate");
  tick_stamp_ = std::make_unique<diagnostic_updater::TimeStampStatus>(
      diagnostic_updater::TimeStampStatusParam(-1.0, 1.0 / cfg.tick_rate + 0.1), "tick stamps");
  updater_->add(*tick_freq_);
  updater_->add(*tick_stamp_);
  pause_srv_ = nh_.advertiseService("set_paused", &PlannerNode::on_set_paused, this);
  estop_srv_ = nh_.advertiseService("emergency_stop", &PlannerNode::on_emergency_stop, this);
  if (per_robot_topics_)
    for (int r = 0; r < cfg.num_robots; ++r)
      robot_pubs_.push_back(nh_.advertise<gd_rhcr_msgs::StepCommand>("robot_" + std::to_string(r) + "/step_command", 10));
  states_sub_ = nh_.subscribe("robot_states", 10, &PlannerNode::on_states, this);
  tasks_sub_ = nh_.subscribe("tasks", 1000, &PlannerNode::on_task, this);
  submit_srv_ = nh_.advertiseService("submit_task", &PlannerNode::on_submit, this);
  cancel_srv_ = nh_.advertiseService("cancel_task", &PlannerNode::on_cancel, this);
  list_srv_ = nh_.advertiseService("list_tasks", &PlannerNode::on_list, this);
  action_ = std::make_unique<DeliveryServer>(
      nh_, "delivery", [this](DeliveryServer::GoalHandle gh) { on_goal(gh); },
      [this](DeliveryServer::GoalHandle gh) { on_cancel_goal(gh); }, false);
  action_->start();
}

void PlannerNode::start_timers(ros::CallbackQueue* tick_queue) {
  const FleetConfig& cfg = fleet_->config();
  ros::TimerOptions opts(ros::Duration(1.0 / cfg.tick_rate), [this](const ros::TimerEvent& ev) { on_tick(ev); },
                         tick_queue);
  tick_timer_ = nh_.createTimer(opts);
  if (cfg.dispatch_rate > 0) {  // on the tick thread, so it never runs during a tick
    ros::TimerOptions d(ros::Duration(1.0 / cfg.dispatch_rate), [this](const ros::TimerEvent& ev) { on_dispatch(ev); },
                        tick_queue);
    dispatch_timer_ = nh_.createTimer(d);
  }
  diag_timer_ = nh_.createTimer(ros::Duration(0.25), [this](const ros::TimerEvent&) { updater_->update(); });
  // Live tuning; the first callback brings the server's starting values.
  reconfigure_ = std::make_unique<dynamic_reconfigure::Server<PlannerConfig>>(reconfigure_mutex_, pnh_);
  reconfigure_->setCallback([this](PlannerConfig& c, uint32_t level) { on_reconfigure(c, level); });
}

void PlannerNode::publish_static(const gdrhcr::MapdCells& mapd) {
  const auto og = occupancy_grid(*map_, frame_id_, ros::Time::now());
  map_pub_.publish(og);
  mapd_pub_.publish(mapd_message(map_->grid, mapd, og.header));
}

void PlannerNode::on_states(const gd_rhcr_msgs::RobotStateArray::ConstPtr& msg) {
  std::string error;
  fleet_->update_robots(robot_reports(*msg), ros::Time::now().toSec(), error);
}

void PlannerNode::on_task(const gd_rhcr_msgs::Task::ConstPtr& m) {
  fleet_->submit({m->pickup_x, m->pickup_y, m->delivery_x, m->delivery_y, m->priority, m->id});
  publish_events();
}

bool PlannerNode::on_submit(gd_rhcr_msgs::SubmitTask::Request& req, gd_rhcr_msgs::SubmitTask::Response& res) {
  const auto& t = req.task;
  const auto r = fleet_->submit({t.pickup_x, t.pickup_y, t.delivery_x, t.delivery_y, t.priority, t.id});
  res.accepted = r.accepted, res.task_id = r.task_id, res.reason = r.reason;
  publish_events();
  return true;
}

bool PlannerNode::on_cancel(gd_rhcr_msgs::CancelTask::Request& req, gd_rhcr_msgs::CancelTask::Response& res) {
  res.success = fleet_->cancel(req.task_id, res.reason);
  publish_events();
  return true;
}

bool PlannerNode::on_list(gd_rhcr_msgs::ListTasks::Request& req, gd_rhcr_msgs::ListTasks::Response& res) {
  for (auto& [id, t] : fleet_->tasks(req.include_finished)) {
    res.tasks.push_back(task_message(t));
    res.statuses.push_back(status_message(t));
  }
  return true;
}

void PlannerNode::on_goal(DeliveryServer::GoalHandle gh) {
  {
    std::lock_guard<std::mutex> lock(events_mutex_);  // the goal is known before its events go out
    auto g = gh.getGoal();
    const auto r = fleet_->submit({g->pickup_x, g->pickup_y, g->delivery_x, g->delivery_y, g->priority, 0});
    if (r.accepted) {
      gh.setAccepted();
      goal_of_task_.emplace(r.task_id, gh);
    } else {
      gd_rhcr_msgs::DeliveryResult res;
      res.final_state = kFailed, res.reason = r.reason, res.task_id = r.task_id, res.robot_id = -1;
      gh.setRejected(res, r.reason);
    }
  }
  publish_events();
}

void PlannerNode::on_cancel_goal(DeliveryServer::GoalHandle gh) {
  uint64_t task = 0;
  {
    std::lock_guard<std::mutex> lock(events_mutex_);
    for (auto& [id, handle] : goal_of_task_)
      if (handle == gh) task = id;
  }
  std::string reason;
  if (task) fleet_->cancel(task, reason);  // the CANCELLED event finishes the goal
  publish_events();
}

// Task status changes (journaled by the manager first) on task_status and to their goals.
void PlannerNode::publish_events() {
  std::lock_guard<std::mutex> lock(events_mutex_);
  const ros::Time now = ros::Time::now();
  for (auto& e : fleet_->take_events()) {
    gd_rhcr_msgs::TaskStatus st;
    st.header.stamp = now;
    st.task_id = e.task_id, st.state = e.state, st.robot_id = e.robot, st.reason = e.reason;
    status_pub_.publish(st);
    auto it = goal_of_task_.find(e.task_id);
    if (it == goal_of_task_.end()) continue;
    auto& gh = it->second;
    if (task_finished(e.state)) {
      gd_rhcr_msgs::DeliveryResult res;
      res.final_state = e.state, res.reason = e.reason, res.task_id = e.task_id, res.robot_id = e.robot;
      if (e.state == kDelivered) gh.setSucceeded(res);
      else if (e.state == kCancelled) gh.setCanceled(res, e.reason);
      else gh.setAborted(res, e.reason);
      goal_of_task_.erase(it);
    } else {
      gd_rhcr_msgs::DeliveryFeedback fb;
      fb.state = e.state, fb.robot_id = e.robot, fb.task_id = e.task_id;
      fb.distance_left = fleet_->distance_left(e.task_id);
      gh.publishFeedback(fb);
    }
  }
}

void PlannerNode::on_tick(const ros::TimerEvent& ev) {
  const bool view = publish_markers_ && markers_pub_.getNumSubscribers() > 0;
  const TickResult r = fleet_->tick(ros::Time::now().toSec(), ros::WallTime::now().toSec(), view);
  publish_events();
  if (!r.stepped) return;
  const ros::Time stamp = ev.current_real.isZero() ? ros::Time::now() : ev.current_real;
  publish_commands(r.commands, r.tick, stamp, false);
  auto st = stats_message(r.stats);
  st.header.stamp = stamp;
  st.tick = r.tick;
  stats_pub_.publish(st);
  if (!r.groups.empty()) groups_pub_.publish(group_array(r, frame_id_, stamp));
  if (!view) return;
  std::lock_guard<std::mutex> lock(markers_mutex_);
  auto arr = markers_->update(r.view);
  for (auto& m : arr.markers) m.header.stamp = stamp;
  if (!arr.markers.empty()) markers_pub_.publish(arr);
}

// Between ticks: robots that reported arrival let the robots queued behind them go at once; only
// their new commands are published, on step_command_updates, with the last tick's number.
void PlannerNode::on_dispatch(const ros::TimerEvent& ev) {
  const auto commands = fleet_->between_ticks();
  if (commands.empty()) return;
  publish_commands(commands, fleet_->tick_count(), ev.current_real.isZero() ? ros::Time::now() : ev.current_real,
                   true);
}

void PlannerNode::publish_commands(const std::vector<RobotCommand>& commands, uint64_t tick, const ros::Time& stamp,
                                   bool between_ticks) {
  const auto cmds = step_commands(commands, *map_, frame_id_, tick, 1.0 / fleet_->config().tick_rate, stamp);
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

void PlannerNode::diagnose(diagnostic_updater::DiagnosticStatusWrapper& s) {
  std::vector<std::pair<std::string, std::string>> values;
  const Health h = fleet_->diagnose(ros::WallTime::now().toSec(), values);
  s.summary(h.level, h.message);
  for (auto& [k, v] : values) s.add(k, v);
}

bool PlannerNode::on_set_paused(gd_rhcr_msgs::SetPaused::Request& req, gd_rhcr_msgs::SetPaused::Response& res) {
  const std::string err = fleet_->set_paused(req.robot_id, req.paused);
  res.success = err.empty();
  res.message = err.empty() ? fleet_->operator_summary() : err;
  return true;
}

bool PlannerNode::on_emergency_stop(gd_rhcr_msgs::EmergencyStop::Request& req,
                                    gd_rhcr_msgs::EmergencyStop::Response& res) {
  fleet_->set_emergency_stop(req.engage);
  res.success = true;
  res.message = fleet_->operator_summary();
  updater_->force_update();
  return true;
}

// dynamic_reconfigure (main thread): a bad value is put back to the live one (the server then
// shows what runs) and logged by the manager; changes apply at the start of the next tick.
void PlannerNode::on_reconfigure(PlannerConfig& c, uint32_t) {
  LiveConfig l = live_of(c);
  fleet_->reconfigure(l);
  copy_live(l, c);
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
