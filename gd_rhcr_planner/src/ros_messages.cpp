// Conversions between the fleet manager's structs and ROS messages (ros_messages.hpp).
#include "gd_rhcr_planner/ros_messages.hpp"

#include <cmath>
#include <sstream>

#include <ros/console.h>

namespace gd_rhcr_planner {

std::string xmlrpc_to_string(XmlRpc::XmlRpcValue& v, const std::string& name) {
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
    default: throw gdrhcr::ParamError("planner parameter ~" + name + " has an unsupported type");
  }
}

void ros_log(LogLevel level, const std::string& msg) {
  switch (level) {
    case LogLevel::kDebug: ROS_DEBUG("%s", msg.c_str()); break;
    case LogLevel::kInfo: ROS_INFO("%s", msg.c_str()); break;
    case LogLevel::kWarn: ROS_WARN("%s", msg.c_str()); break;
    case LogLevel::kError: ROS_ERROR("%s", msg.c_str()); break;
  }
}

gdrhcr::Heading heading_of_message(uint8_t h) {
  if (h == gd_rhcr_msgs::RobotState::HEADING_NONE) return gdrhcr::kNoHeading;
  return h <= gd_rhcr_msgs::RobotState::HEADING_NORTH ? static_cast<gdrhcr::Heading>(h - 1) : gdrhcr::kNumHeadings;
}

uint8_t heading_message(gdrhcr::Heading h) {
  return h == gdrhcr::kNoHeading ? gd_rhcr_msgs::RobotState::HEADING_NONE : static_cast<uint8_t>(h + 1);
}

uint8_t action_message(gdrhcr::Action a) {
  switch (a) {
    case gdrhcr::Action::kForward: return gd_rhcr_msgs::StepCommand::ACTION_FORWARD;
    case gdrhcr::Action::kClockwise: return gd_rhcr_msgs::StepCommand::ACTION_ROTATE_CW;
    case gdrhcr::Action::kCounterClockwise: return gd_rhcr_msgs::StepCommand::ACTION_ROTATE_CCW;
    case gdrhcr::Action::kWait: break;
  }
  return gd_rhcr_msgs::StepCommand::ACTION_WAIT;
}

std::vector<RobotReport> robot_reports(const gd_rhcr_msgs::RobotStateArray& msg) {
  std::vector<RobotReport> out;
  out.reserve(msg.robots.size());
  const double stamp = msg.header.stamp.toSec();
  for (const auto& s : msg.robots) {
    const auto& p = s.pose;
    RobotReport r;
    r.id = s.id, r.x = s.x, r.y = s.y, r.mode = s.mode, r.moving = s.moving, r.stamp = stamp;
    r.entering_known = s.entering_known, r.entering_x = s.entering_x, r.entering_y = s.entering_y;
    r.heading = heading_of_message(s.heading);  // > HEADING_NORTH: kNumHeadings, refused by the manager
    r.pose_finite = std::isfinite(p.position.x) && std::isfinite(p.position.y) && std::isfinite(p.position.z) &&
                    std::isfinite(p.orientation.x) && std::isfinite(p.orientation.y) &&
                    std::isfinite(p.orientation.z) && std::isfinite(p.orientation.w);
    out.push_back(r);
  }
  return out;
}

LiveConfig live_of(const PlannerConfig& c) {
  LiveConfig l;
  l.V = c.V, l.H = c.H, l.c_soft = c.c_soft, l.K_threshold = c.K_threshold, l.solver = c.solver;
  l.plan_deadline = c.plan_deadline, l.offline_timeout = c.offline_timeout, l.dispatcher = c.dispatcher;
  l.dispatch_switch_margin = c.dispatch_switch_margin, l.dispatch_finish_horizon = c.dispatch_finish_horizon;
  return l;
}

void copy_live(const LiveConfig& l, PlannerConfig& c) {
  c.V = l.V, c.H = l.H, c.c_soft = l.c_soft, c.K_threshold = l.K_threshold, c.solver = l.solver;
  c.plan_deadline = l.plan_deadline, c.offline_timeout = l.offline_timeout, c.dispatcher = l.dispatcher;
  c.dispatch_switch_margin = l.dispatch_switch_margin, c.dispatch_finish_horizon = l.dispatch_finish_horizon;
}

gd_rhcr_msgs::PlannerStats stats_message(const TickStats& s) {
  gd_rhcr_msgs::PlannerStats m;
  m.planner = s.planner, m.num_robots = s.num_robots, m.planned = s.planned, m.plan_time = s.plan_time;
  m.step_time = s.step_time, m.tick_period = s.tick_period, m.overruns = s.overruns;
  m.skipped_ticks = s.skipped_ticks, m.forced_waits = s.forced_waits, m.tasks_queued = s.tasks_queued;
  m.tasks_active = s.tasks_active, m.tasks_delivered = s.tasks_delivered, m.tasks_failed = s.tasks_failed;
  m.num_groups = s.num_groups, m.planner_stats_json = s.planner_stats_json, m.fallback = s.fallback;
  m.fallback_ticks = s.fallback_ticks, m.offline_robots = s.offline_robots, m.planner_config = s.planner_config;
  m.reconfigures = s.reconfigures, m.deliveries_per_minute = s.deliveries_per_minute;
  m.group_size_max = s.group_size_max, m.group_size_mean = s.group_size_mean;
  const PlannerFigures& f = s.figures;
  m.solver_calls = f.solver_calls, m.solver_failures = f.solver_failures, m.solver_timeouts = f.solver_timeouts;
  m.pbs_nodes = f.pbs_nodes, m.solver_time_mean = f.solver_time_mean;
  m.groups_replanned_per_step = f.groups_replanned_per_step, m.cache_reuses = f.cache_reuses;
  m.threshold_fallbacks = f.threshold_fallbacks, m.failure_fallbacks = f.failure_fallbacks, m.repairs = f.repairs;
  const DispatchStats& d = s.dispatch;
  m.dispatcher = s.dispatcher, m.dispatch_robots = d.robots, m.dispatch_tasks = d.tasks;
  m.dispatch_assigned = d.assigned, m.dispatch_reassigned = d.reassigned, m.dispatch_reserved = d.reserved;
  m.dispatch_travel = d.travel, m.dispatch_time = d.time_s;
  m.paused_robots = s.paused_robots, m.emergency_stop = s.emergency_stop;
  return m;
}

gd_rhcr_msgs::StepCommandArray step_commands(const std::vector<RobotCommand>& commands, const LoadedMap& map,
                                             const std::string& frame_id, uint64_t tick, double tick_period,
                                             const ros::Time& stamp) {
  const auto& grid = map.grid;
  gd_rhcr_msgs::StepCommandArray cmds;
  cmds.header.stamp = stamp;
  cmds.header.frame_id = frame_id;
  cmds.tick = tick;
  cmds.tick_period = tick_period;
  for (const RobotCommand& rc : commands) {
    gd_rhcr_msgs::StepCommand c;
    c.robot_id = rc.robot, c.tick = tick, c.next_x = grid.x_of(rc.cell), c.next_y = grid.y_of(rc.cell);
    c.target_pose.position.x = map.frame.world_x(c.next_x);
    c.target_pose.position.y = map.frame.world_y(c.next_y);
    c.next_heading = heading_message(rc.heading);
    const double yaw = rc.heading == gdrhcr::kNoHeading ? 0.0 : heading_yaw(rc.heading);
    c.target_pose.orientation.z = std::sin(yaw / 2);
    c.target_pose.orientation.w = std::cos(yaw / 2);
    c.action = action_message(rc.action);
    c.mode = rc.mode, c.task_id = rc.task;
    cmds.commands.push_back(c);
  }
  return cmds;
}

gd_rhcr_msgs::GroupArray group_array(const TickResult& r, const std::string& frame_id, const ros::Time& stamp) {
  gd_rhcr_msgs::GroupArray msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame_id;
  msg.tick = r.tick;
  for (size_t g = 0; g < r.groups.size(); ++g) {
    gd_rhcr_msgs::Group gm;
    gm.members.assign(r.groups[g].begin(), r.groups[g].end());
    gm.size = gm.members.size();
    gm.solver = g < r.group_solvers.size() ? r.group_solvers[g] : "";
    msg.groups.push_back(gm);
  }
  return msg;
}

nav_msgs::OccupancyGrid occupancy_grid(const LoadedMap& map, const std::string& frame_id, const ros::Time& stamp) {
  const auto& grid = map.grid;
  nav_msgs::OccupancyGrid og;
  og.header.frame_id = frame_id;
  og.header.stamp = stamp;
  og.info.map_load_time = stamp;
  og.info.resolution = static_cast<float>(map.frame.resolution);
  og.info.width = grid.width();
  og.info.height = grid.height();
  og.info.origin.position.x = map.frame.origin_x;
  og.info.origin.position.y = map.frame.origin_y;
  og.info.origin.orientation.w = 1.0;
  og.data.resize(static_cast<size_t>(grid.width()) * grid.height());
  for (int r = 0; r < grid.height(); ++r)
    for (int x = 0; x < grid.width(); ++x)
      og.data[static_cast<size_t>(r) * grid.width() + x] = grid.is_free(grid.cell(x, grid.height() - 1 - r)) ? 0 : 100;
  return og;
}

gd_rhcr_msgs::MapdCells mapd_message(const gdrhcr::Grid& grid, const gdrhcr::MapdCells& mapd,
                                     const std_msgs::Header& header) {
  gd_rhcr_msgs::MapdCells mc;
  mc.header = header;
  mc.rule = mapd.rule;
  for (auto c : mapd.pickups) mc.pickup_x.push_back(grid.x_of(c)), mc.pickup_y.push_back(grid.y_of(c));
  for (auto c : mapd.deliveries) mc.delivery_x.push_back(grid.x_of(c)), mc.delivery_y.push_back(grid.y_of(c));
  return mc;
}

gd_rhcr_msgs::Task task_message(const TaskRecord& t) {
  gd_rhcr_msgs::Task m;
  m.id = t.id, m.pickup_x = t.pickup_x, m.pickup_y = t.pickup_y, m.delivery_x = t.delivery_x;
  m.delivery_y = t.delivery_y, m.priority = t.priority;
  return m;
}

gd_rhcr_msgs::TaskStatus status_message(const TaskRecord& t) {
  gd_rhcr_msgs::TaskStatus s;
  s.task_id = t.id, s.state = t.state, s.robot_id = t.robot, s.reason = t.reason;
  return s;
}

}  // namespace gd_rhcr_planner
