// Conversions between the fleet manager's plain structs (fleet_manager.hpp) and the node's ROS
// messages and dynamic_reconfigure config. No node handle: tested without a master.
#pragma once

#include <string>
#include <vector>

#include <gd_rhcr_msgs/GroupArray.h>
#include <gd_rhcr_msgs/MapdCells.h>
#include <gd_rhcr_msgs/PlannerStats.h>
#include <gd_rhcr_msgs/RobotStateArray.h>
#include <gd_rhcr_msgs/StepCommandArray.h>
#include <gd_rhcr_msgs/Task.h>
#include <gd_rhcr_msgs/TaskStatus.h>
#include <gd_rhcr_planner/PlannerConfig.h>
#include <nav_msgs/OccupancyGrid.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include "gd_rhcr_planner/fleet_manager.hpp"
#include "gd_rhcr_planner/map_loader.hpp"
#include "gdrhcr/task_stream.hpp"

namespace gd_rhcr_planner {

// A parameter's value as the core's Params read it; throws gdrhcr::ParamError naming `name` for
// a list or a dictionary.
std::string xmlrpc_to_string(XmlRpc::XmlRpcValue& v, const std::string& name);
// The fleet manager's log lines through rosconsole.
void ros_log(LogLevel level, const std::string& msg);
// Headings between RobotState.HEADING_* (0 none, 1..4 east, south, west, north) and the planner's
// (action_model.hpp: kNoHeading, 0..3 in the same order; a message value above 4 becomes
// kNumHeadings, which the manager refuses); yaws: heading_yaw (map_loader.hpp).
gdrhcr::Heading heading_of_message(uint8_t h);
uint8_t heading_message(gdrhcr::Heading h);
uint8_t action_message(gdrhcr::Action a);  // StepCommand.ACTION_*
// The reports of a RobotStateArray (its header stamp on each; pose checked for finiteness).
std::vector<RobotReport> robot_reports(const gd_rhcr_msgs::RobotStateArray& msg);
LiveConfig live_of(const PlannerConfig& c);
void copy_live(const LiveConfig& l, PlannerConfig& c);
gd_rhcr_msgs::PlannerStats stats_message(const TickStats& s);
gd_rhcr_msgs::StepCommandArray step_commands(const std::vector<RobotCommand>& commands, const LoadedMap& map,
                                             const std::string& frame_id, uint64_t tick, double tick_period,
                                             const ros::Time& stamp);
gd_rhcr_msgs::GroupArray group_array(const TickResult& r, const std::string& frame_id, const ros::Time& stamp);
// The map as an OccupancyGrid (row 0 at the bottom, REP 103) and the MAPD stations.
nav_msgs::OccupancyGrid occupancy_grid(const LoadedMap& map, const std::string& frame_id, const ros::Time& stamp);
gd_rhcr_msgs::MapdCells mapd_message(const gdrhcr::Grid& grid, const gdrhcr::MapdCells& mapd,
                                     const std_msgs::Header& header);
gd_rhcr_msgs::Task task_message(const TaskRecord& t);
gd_rhcr_msgs::TaskStatus status_message(const TaskRecord& t);

}  // namespace gd_rhcr_planner
