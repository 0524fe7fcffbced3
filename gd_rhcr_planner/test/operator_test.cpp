// Operator controls, node health for diagnostic_updater, planner figures as fields, the
// throughput meter and the rviz markers builder (issue 14). No ROS master needed.
#include <gtest/gtest.h>

#include <cmath>

#include "gd_rhcr_planner/fleet_markers.hpp"
#include "gd_rhcr_planner/fleet_stats.hpp"
#include "gd_rhcr_planner/health.hpp"
#include "gd_rhcr_planner/operator_control.hpp"
#include "gd_rhcr_planner/ros_messages.hpp"

using namespace gd_rhcr_planner;

TEST(OperatorControl, PauseResumeAndEmergencyStop) {
  OperatorControl op(4);
  EXPECT_EQ(op.summary(), "running");
  EXPECT_TRUE(op.unavailable().empty());
  EXPECT_EQ(op.set_paused(2, true), "");
  EXPECT_TRUE(op.holds(2));
  EXPECT_FALSE(op.holds(1));
  EXPECT_EQ(op.mode(2, 1), kModePaused);
  EXPECT_EQ(op.mode(1, 1), 1);
  EXPECT_EQ(op.mode(2, 3), 3) << "offline stays offline";
  EXPECT_EQ(op.unavailable(), std::vector<uint8_t>({0, 0, 1, 0}));
  EXPECT_EQ(op.summary(), "1 robots paused");
  const std::string err = op.set_paused(7, true);
  EXPECT_NE(err.find("unknown robot id 7"), std::string::npos) << err;
  EXPECT_NE(op.set_paused(-2, true), "");
  EXPECT_EQ(op.set_paused(-1, true), "");
  EXPECT_EQ(op.paused_count(), 4);
  EXPECT_EQ(op.summary(), "fleet paused");
  EXPECT_EQ(op.set_paused(-1, false), "");  // resuming the fleet resumes robot 2 as well
  EXPECT_FALSE(op.any_held());
  op.set_emergency_stop(true);
  EXPECT_TRUE(op.holds(0));
  EXPECT_EQ(op.mode(0, 2), kModeStopped);
  EXPECT_TRUE(op.unavailable().empty()) << "an emergency stop keeps every assignment";
  EXPECT_EQ(op.summary(), "EMERGENCY STOP");
  op.set_emergency_stop(false);
  EXPECT_EQ(op.summary(), "running");
}

TEST(Health, ProblemsShowWhileTheyHappenAndClear) {
  HealthMonitor m;
  HealthCounters c;
  c.missing_robots = 3;
  auto h = m.update(c);
  EXPECT_EQ(h.level, 1);
  EXPECT_NE(h.message.find("3 robots not reporting"), std::string::npos);
  c.missing_robots = 0;
  c.overruns = 2;
  h = m.update(c);
  EXPECT_EQ(h.level, 1);
  EXPECT_NE(h.message.find("2 tick overruns"), std::string::npos) << h.message;
  h = m.update(c);  // no new overrun: clears
  EXPECT_EQ(h.level, 0);
  EXPECT_EQ(h.message, "planning");
  c.rejected_plans = 1;
  c.fallback_ticks = 5;
  h = m.update(c);
  EXPECT_EQ(h.level, 2);
  EXPECT_NE(h.message.find("rejected"), std::string::npos);
  EXPECT_NE(h.message.find("5 ticks past the plan deadline"), std::string::npos);
  h = m.update(c);
  EXPECT_EQ(h.level, 0);
  c.emergency_stop = true;
  c.paused_robots = 2;
  h = m.update(c);
  EXPECT_EQ(h.level, 1);
  EXPECT_NE(h.message.find("emergency stop"), std::string::npos);
  EXPECT_NE(h.message.find("2 robots paused"), std::string::npos);
  c.emergency_stop = false;
  c.paused_robots = 0;
  EXPECT_EQ(m.update(c).level, 0);
}

TEST(FleetStats, PlannerFiguresFromEachPlannersJson) {
  auto gd = planner_figures(nlohmann::json::parse(
      R"({"groups":{"mean_count":12.5,"mean_size":1.5,"replanned_per_step":3.0},"cache_reuses":7,
          "primary_calls":40,"primary_time_mean_s":0.002,"pbs_nodes":900,"threshold_fallbacks":2,
          "failure_fallbacks":1,"timeouts":0,"repairs":4})"));
  EXPECT_EQ(gd.solver_calls, 40u);
  EXPECT_EQ(gd.solver_failures, 1u);
  EXPECT_DOUBLE_EQ(gd.groups_mean_count, 12.5);
  EXPECT_DOUBLE_EQ(gd.groups_replanned_per_step, 3.0);
  EXPECT_EQ(gd.cache_reuses, 7u);
  EXPECT_EQ(gd.repairs, 4u);
  EXPECT_EQ(gd.pbs_nodes, 900u);
  auto rh = planner_figures(nlohmann::json::parse(
      R"({"solver_calls":10,"solver_failures":3,"solver_timeouts":1,"solver_time_mean_s":0.5})"));
  EXPECT_EQ(rh.solver_calls, 10u);
  EXPECT_EQ(rh.solver_failures, 3u);
  EXPECT_EQ(rh.solver_timeouts, 1u);
  EXPECT_DOUBLE_EQ(rh.solver_time_mean, 0.5);
  auto none = planner_figures(nlohmann::json::object());
  EXPECT_EQ(none.solver_calls, 0u);
  EXPECT_EQ(planner_figures(nlohmann::json("nonsense")).solver_calls, 0u);
}

TEST(FleetStats, DeliveriesPerMinuteOverTheWindow) {
  ThroughputMeter m(60.0);
  EXPECT_EQ(m.per_minute(), 0.0);
  for (int t = 0; t <= 120; ++t) m.add(t, t < 60 ? 0 : 2 * (t - 60));  // nothing, then 2 per second
  EXPECT_NEAR(m.per_minute(), 120.0, 1e-9) << "only the last 60 s count";
}

namespace {
gdrhcr::Grid small() { return gdrhcr::Grid::from_rows({"......", ".@@@@.", "......"}); }
MapFrame frame_of(const gdrhcr::Grid& g) {
  MapFrame f;
  f.height = g.height();
  return f;
}
int count_ns(const visualization_msgs::MarkerArray& a, const std::string& ns) {
  int k = 0;
  for (auto& m : a.markers) k += m.ns == ns;
  return k;
}
const visualization_msgs::Marker* find(const visualization_msgs::MarkerArray& a, const std::string& ns, int id = 0) {
  for (auto& m : a.markers)
    if (m.ns == ns && m.id == id) return &m;
  return nullptr;
}
}  // namespace

TEST(FleetMarkers, LayersOrientationAndOnlyChangesAreResent) {
  auto g = small();
  FleetMarkers fm(g, frame_of(g), {});
  fm.set_stations({g.cell(0, 0)}, {g.cell(5, 2)});
  FleetView v;
  v.pos = {g.cell(0, 0), g.cell(3, 2)};
  v.next = {g.cell(1, 0), g.cell(3, 2)};
  v.goal = {g.cell(5, 0), g.cell(0, 2)};
  v.group_of = {0, 0};
  v.offline = {0, 0};
  v.held = {0, 1};
  v.paths = {{g.cell(0, 0), g.cell(1, 0), g.cell(2, 0)}, {}};
  v.task_pickups = {g.cell(5, 0)};
  v.overlay = overlay_text(7, 12.5, 3, 1, 1, 0.0012, "gd-rhcr", "batch", "1 robots paused");
  auto a = fm.update(v);
  for (const char* ns : {"robots", "groups", "paths", "goal_lines", "stations", "tasks", "operator", "labels", "overlay"})
    EXPECT_GT(count_ns(a, ns), 0) << ns;
  const auto* robots = find(a, "robots");
  ASSERT_NE(robots, nullptr);
  ASSERT_EQ(robots->points.size(), 6u);  // a triangle per robot
  EXPECT_GT(robots->points[0].x, 0.5 + 0.4) << "robot 0 points +x, towards its next cell";
  EXPECT_EQ(find(a, "goal_lines")->action, visualization_msgs::Marker::DELETE) << "no goal lines unless asked";
  EXPECT_EQ(find(a, "paths")->points.size(), 4u) << "two path segments along the aisle";
  EXPECT_EQ(find(a, "groups")->points.size(), 2u) << "one link between the two members";
  EXPECT_EQ(find(a, "operator", 0)->points.size(), 8u) << "robot 1 framed as paused";
  EXPECT_NE(find(a, "overlay")->text.find("12.5 deliveries/min"), std::string::npos);
  EXPECT_NE(find(a, "overlay")->text.find("open tasks 3"), std::string::npos);
  // Same view again: nothing to send.
  EXPECT_TRUE(fm.update(v).markers.empty());
  // A robot moves: robots, groups, paths, labels change; stations do not.
  v.pos[0] = g.cell(1, 0);
  v.next[0] = g.cell(2, 0);
  a = fm.update(v);
  EXPECT_EQ(count_ns(a, "stations"), 0);
  EXPECT_EQ(count_ns(a, "robots"), 1);
  EXPECT_EQ(count_ns(a, "overlay"), 0);
  EXPECT_EQ(fm.current().size(), 13u);
  // Emergency stop: a red frame around the map.
  v.emergency_stop = true;
  a = fm.update(v);
  ASSERT_NE(find(a, "operator", 1), nullptr);
  EXPECT_EQ(find(a, "operator", 1)->points.size(), 8u);
}

// Turning robots (issue 23): a robot's triangle points along the heading it reports, also at
// rest and against its next move's direction: north (row up) is +y in the map frame, south -y.
TEST(FleetMarkers, RobotsPointAlongTheirReportedHeading) {
  auto g = small();
  FleetMarkers fm(g, frame_of(g), {});
  FleetView v;
  v.pos = {g.cell(0, 0), g.cell(3, 2), g.cell(5, 0)};
  v.next = {g.cell(1, 0), g.cell(3, 2), g.cell(5, 0)};
  v.heading = {gdrhcr::kNorth, gdrhcr::kSouth, gdrhcr::kNoHeading};
  v.group_of = {0, 1, 2};
  v.offline = {0, 0, 0};
  v.held = {0, 0, 0};
  v.paths.assign(3, {});
  v.goal.assign(3, gdrhcr::kNoCell);
  auto a = fm.update(v);
  const auto* robots = find(a, "robots");
  ASSERT_NE(robots, nullptr);
  ASSERT_EQ(robots->points.size(), 9u);
  auto centre = [&](Cell c) { return std::make_pair(0.5 + g.x_of(c), 0.5 + (g.height() - 1 - g.y_of(c))); };
  // The tip (first point) of each triangle, from its cell's centre.
  const auto c0 = centre(v.pos[0]), c1 = centre(v.pos[1]);
  EXPECT_NEAR(robots->points[0].x, c0.first, 1e-9) << "robot 0 faces north, not its next cell east";
  EXPECT_GT(robots->points[0].y, c0.second + 0.5);
  EXPECT_NEAR(robots->points[3].x, c1.first, 1e-9);
  EXPECT_LT(robots->points[3].y, c1.second - 0.5) << "robot 1 faces south: -y";
  v.heading[0] = gdrhcr::kWest;  // turned: its triangle turns with it
  a = fm.update(v);
  robots = find(a, "robots");
  ASSERT_NE(robots, nullptr);
  EXPECT_LT(robots->points[0].x, c0.first - 0.5);
}

TEST(FleetMarkers, GoalLinesOnlyWhenAskedAndLabelsOnlyForSmallFleets) {
  auto g = small();
  MarkerStyle st;
  st.show_goal_lines = true;
  st.label_limit = 1;
  FleetMarkers fm(g, frame_of(g), st);
  FleetView v;
  v.pos = {g.cell(0, 0), g.cell(3, 2)};
  v.next = v.pos;
  v.goal = {g.cell(5, 0), g.cell(3, 2)};
  auto a = fm.update(v);
  EXPECT_EQ(find(a, "goal_lines")->points.size(), 2u);
  EXPECT_EQ(count_ns(a, "labels"), 0);
}

// The node's conversions (ros_messages.hpp): REP 103 rows (the map's top row is the grid's last),
// cell centres as target poses, live parameters both ways, a list parameter named in its error.
TEST(RosMessages, MapCommandsAndLiveParametersConvert) {
  LoadedMap map{small(), frame_of(small()), "inline", "movingai"};
  const auto og = occupancy_grid(map, "map", ros::Time(1.0));
  ASSERT_EQ(og.data.size(), 18u);
  EXPECT_EQ(og.data[1 * 6 + 1], 100) << "the obstacle row stays in the middle";
  EXPECT_EQ(og.data[0], 0);
  const auto cmds = step_commands({{1, map.grid.cell(5, 0), kToPickup, 7}}, map, "map", 3, 0.5, ros::Time(2.0));
  ASSERT_EQ(cmds.commands.size(), 1u);
  EXPECT_EQ(cmds.commands[0].next_x, 5);
  EXPECT_EQ(cmds.commands[0].next_y, 0);
  EXPECT_DOUBLE_EQ(cmds.commands[0].target_pose.position.x, 5.5);
  EXPECT_DOUBLE_EQ(cmds.commands[0].target_pose.position.y, 2.5) << "row 0 is the top, furthest from the origin";
  EXPECT_EQ(cmds.commands[0].task_id, 7);
  EXPECT_EQ(cmds.commands[0].next_heading, gd_rhcr_msgs::RobotState::HEADING_NONE) << "mapf default: any heading";
  EXPECT_EQ(cmds.commands[0].action, gd_rhcr_msgs::StepCommand::ACTION_WAIT);
  // Headings (issue 23): north is the row above (y - 1 in cells), +y in metres: yaw +pi/2.
  RobotCommand turn{1, map.grid.cell(5, 0), kToPickup, 7, gdrhcr::kNorth, gdrhcr::Action::kCounterClockwise};
  const auto north = step_commands({turn}, map, "map", 3, 0.5, ros::Time(2.0)).commands.at(0);
  EXPECT_EQ(north.next_heading, gd_rhcr_msgs::RobotState::HEADING_NORTH);
  EXPECT_EQ(north.action, gd_rhcr_msgs::StepCommand::ACTION_ROTATE_CCW);
  EXPECT_NEAR(2 * std::atan2(north.target_pose.orientation.z, north.target_pose.orientation.w), M_PI / 2, 1e-9);
  turn.heading = gdrhcr::kSouth;
  const auto south = step_commands({turn}, map, "map", 3, 0.5, ros::Time(2.0)).commands.at(0);
  EXPECT_NEAR(2 * std::atan2(south.target_pose.orientation.z, south.target_pose.orientation.w), -M_PI / 2, 1e-9);
  for (uint8_t h = 0; h <= 4; ++h) EXPECT_EQ(heading_message(heading_of_message(h)), h);
  EXPECT_EQ(heading_of_message(gd_rhcr_msgs::RobotState::HEADING_EAST), gdrhcr::kEast);
  EXPECT_EQ(heading_of_message(gd_rhcr_msgs::RobotState::HEADING_SOUTH), gdrhcr::kSouth);
  EXPECT_EQ(heading_of_message(gd_rhcr_msgs::RobotState::HEADING_NONE), gdrhcr::kNoHeading);
  EXPECT_EQ(heading_of_message(200), gdrhcr::kNumHeadings) << "out of range: refused by the manager";
  PlannerConfig pc = PlannerConfig::__getDefault__();
  LiveConfig l = live_of(pc);
  l.V = 4;
  l.solver = "pibt";
  copy_live(l, pc);
  EXPECT_EQ(pc.V, 4);
  EXPECT_EQ(pc.solver, "pibt");
  XmlRpc::XmlRpcValue list;
  list[0] = 1;
  try {
    xmlrpc_to_string(list, "V");
    FAIL() << "a list was taken as a value";
  } catch (const gdrhcr::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("~V"), std::string::npos);
  }
  TickStats st;
  st.planner = "gd-rhcr";
  st.figures.cache_reuses = 9;
  st.dispatch.assigned = 2;
  const auto m = stats_message(st);
  EXPECT_EQ(m.planner, "gd-rhcr");
  EXPECT_EQ(m.cache_reuses, 9u);
  EXPECT_EQ(m.dispatch_assigned, 2u);
}
