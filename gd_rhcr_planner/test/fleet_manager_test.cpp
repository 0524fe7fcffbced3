// FleetManager (fleet_manager.hpp), tick by tick without ROS: simulated robots that follow their
// commands deliver tasks without ever being sent into a cell another robot stands in; parameters
// are checked against the planner table (a misspelling is an error naming it, on construction
// and on reconfigure, where the old value is kept); operator holds, the task journal across a
// restart, and the node's configuration file.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "gd_rhcr_planner/fleet_manager.hpp"
#include "gdrhcr/map_prep.hpp"

using namespace gd_rhcr_planner;
using gdrhcr::Cell;
using gdrhcr::Grid;

namespace {

Grid warehouse() {
  return Grid::from_rows({
      "............",
      ".@@.@@.@@.@.",
      "............",
      ".@@.@@.@@.@.",
      "............",
  });
}

FleetConfig config(const std::string& planner, int robots) {
  FleetConfig c;
  c.planner = planner;
  c.num_robots = robots;
  c.tick_rate = 10;       // ticks do not wait for the clock here; the deadline bounds a step
  c.plan_deadline = 0.09;
  c.offline_timeout = 1e6;
  c.task_store = "";
  return c;
}

// A fresh path for a task journal (no file there yet).
std::string journal_path() {
  char path[] = "/tmp/fleet_manager_test_XXXXXX";
  const int fd = mkstemp(path);
  if (fd >= 0) close(fd);
  std::remove(path);
  return path;
}

// Robots that follow their commands at once: each tick they report the cell they were sent to.
struct SimFleet {
  FleetManager& fm;
  std::vector<std::pair<int, int>> xy;
  double now = 0;
  int conflicts = 0;  // commands into a cell another robot stands in

  void report() {
    std::string err;
    for (size_t r = 0; r < xy.size(); ++r)
      ASSERT_TRUE(fm.update_robot(r, xy[r].first, xy[r].second, false, false, now, err)) << err;
  }
  void follow(const std::vector<RobotCommand>& commands) {
    const Grid& g = fm.grid();
    std::map<Cell, int> at;
    for (size_t r = 0; r < xy.size(); ++r) at[g.cell(xy[r].first, xy[r].second)] = static_cast<int>(r);
    std::set<Cell> targets;
    for (const auto& c : commands) {
      auto it = at.find(c.cell);
      if (it != at.end() && it->second != c.robot) ++conflicts;
      EXPECT_TRUE(targets.insert(c.cell).second) << "two robots sent into one cell";
      EXPECT_TRUE(g.step_allowed(g.cell(xy[c.robot].first, xy[c.robot].second), c.cell));
    }
    for (const auto& c : commands) xy[c.robot] = {g.x_of(c.cell), g.y_of(c.cell)};
  }
  TickResult step(bool view = false) {
    now += 0.001;
    report();
    TickResult r = fm.tick(now, now, view);
    follow(r.commands);
    report();
    follow(fm.between_ticks());
    return r;
  }
};

}  // namespace

TEST(FleetManager, WholeTicksDeliverTasksAndNeverSendARobotIntoAnother) {
  const Grid g = warehouse();
  for (const char* planner : {"pibt", "gd-rhcr", "rhcr"}) {
    FleetManager fm(g, config(planner, 4));
    SimFleet sim{fm, {{0, 0}, {11, 0}, {0, 4}, {11, 4}}};
    for (int k = 0; k < 6; ++k)
      ASSERT_TRUE(fm.submit({k % 12, 2, (11 - 2 * k) % 12, (k % 2) * 4, 0, 0}).accepted) << planner;
    uint64_t delivered = 0;
    for (int t = 0; t < 120; ++t) {
      TickResult r = sim.step(t % 10 == 0);
      ASSERT_TRUE(r.stepped) << planner << " tick " << t << ": " << r.skip_reason;
      EXPECT_EQ(r.tick, static_cast<uint64_t>(t + 1));
      delivered = r.stats.tasks_delivered;
      if (t % 10 == 0) {
        EXPECT_EQ(r.view.pos.size(), 4u);
        EXPECT_NE(r.view.overlay.find(planner), std::string::npos);
      }
    }
    EXPECT_EQ(sim.conflicts, 0) << planner;
    EXPECT_EQ(delivered, 6u) << planner;
    size_t delivered_events = 0;
    for (auto& e : fm.take_events()) delivered_events += e.state == kDelivered;
    EXPECT_EQ(delivered_events, 6u) << planner;
    EXPECT_TRUE(fm.tasks(false).empty()) << planner;
  }
}

TEST(FleetManager, NoStepUntilEveryRobotReportedOrTheWaitIsOver) {
  const Grid g = warehouse();
  FleetConfig c = config("pibt", 2);
  c.offline_timeout = 0.5;
  FleetManager fm(g, c);
  std::string err;
  ASSERT_TRUE(fm.update_robot(0, 0, 0, false, false, 0.0, err));
  EXPECT_FALSE(fm.tick(0.1, 0.1, false).stepped) << "robot 1 never reported";
  ASSERT_TRUE(fm.update_robot(0, 0, 0, false, false, 0.6, err));
  const auto r = fm.tick(0.6, 0.6, false);
  EXPECT_TRUE(r.stepped) << "after the offline timeout the reported robots move";
  std::vector<std::pair<std::string, std::string>> values;
  fm.diagnose(0.6, values);
  bool told = false;
  for (auto& [k, v] : values) told |= k == "last problem" && v.find("never reported") != std::string::npos;
  EXPECT_TRUE(told);
}

TEST(FleetManager, UnknownOrBadPlannerParametersAreErrorsNamingThem) {
  const Grid g = warehouse();
  FleetConfig c = config("gd-rhcr", 2);
  c.planner_params.set("c_sotf", "2");
  try {
    FleetManager fm(g, c);
    FAIL() << "a misspelt parameter was accepted";
  } catch (const gdrhcr::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("c-sotf"), std::string::npos) << e.what();
  }
  FleetConfig d = config("gd-rhcr", 2);
  d.planner_params.set("V", "-3");
  EXPECT_THROW(FleetManager(g, d), gdrhcr::ParamError);
  FleetConfig p = config("no-such-planner", 2);
  EXPECT_THROW(FleetManager(g, p), gdrhcr::ParamError);
  FleetConfig t = config("pibt", 2);
  t.tick_rate = 0;
  EXPECT_THROW(FleetManager(g, t), gdrhcr::ParamError);
  FleetConfig u = config("pibt", 2);
  u.catch_up = -1;
  try {
    FleetManager fm(g, u);
    FAIL() << "a negative catch_up was accepted";
  } catch (const gdrhcr::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("~catch_up"), std::string::npos) << e.what();
  }
}

TEST(FleetManager, NodeParameterNamesAreCheckedAgainstTheTables) {
  EXPECT_EQ(classify_node_param("tick_rate", "gd-rhcr"), NodeParamKind::kNode);
  EXPECT_EQ(classify_node_param("V", "gd-rhcr"), NodeParamKind::kPlanner);
  EXPECT_EQ(classify_node_param("c_soft", "gd-rhcr"), NodeParamKind::kPlanner);
  EXPECT_EQ(classify_node_param("alpha", "gd-rhcr"), NodeParamKind::kOtherPlanner);
  EXPECT_EQ(classify_node_param("alpha", "rhcr"), NodeParamKind::kPlanner);
  try {
    classify_node_param("tick_rat", "gd-rhcr");
    FAIL() << "a misspelt node parameter was accepted";
  } catch (const gdrhcr::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("~tick_rat"), std::string::npos) << e.what();
  }
  EXPECT_THROW(classify_node_param("execution", "pibt"), gdrhcr::ParamError) << "the lock-step mode is gone";
}

// config/fleet.yaml serves every planner: each key is the node's or some planner's.
TEST(FleetManager, TheNodeConfigurationFileUsesKnownParameters) {
  const YAML::Node yaml = YAML::LoadFile(std::string(GD_RHCR_REPO_DIR) + "/config/fleet.yaml");
  ASSERT_TRUE(yaml.IsMap());
  int keys = 0;
  for (auto it = yaml.begin(); it != yaml.end(); ++it, ++keys) {
    const std::string name = it->first.as<std::string>();
    for (const char* planner : {"pibt", "rhcr", "gd-rhcr"})
      EXPECT_NO_THROW(classify_node_param(name, planner)) << name;
  }
  EXPECT_GT(keys, 10);
}

TEST(FleetManager, ReconfigureRejectsBadValuesKeepingTheOldAndAppliesGoodOnesAtTheNextTick) {
  const Grid g = warehouse();
  FleetManager fm(g, config("gd-rhcr", 2));
  SimFleet sim{fm, {{0, 0}, {11, 4}}};
  sim.step();
  LiveConfig c = fm.live_config();
  const LiveConfig before = c;
  c.solver = "magic";
  auto errors = fm.reconfigure(c);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("solver"), std::string::npos) << errors[0];
  EXPECT_EQ(c.solver, before.solver) << "the old value is put back";
  c.plan_deadline = 5.0;  // longer than the tick period
  errors = fm.reconfigure(c);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("plan_deadline"), std::string::npos);
  EXPECT_EQ(c.plan_deadline, before.plan_deadline);
  c.V = 3;
  EXPECT_TRUE(fm.reconfigure(c).empty());
  EXPECT_NE(fm.planner_config_string().find("V=2"), std::string::npos) << "applied at the next tick";
  const auto r = sim.step();
  EXPECT_NE(r.stats.planner_config.find("V=3"), std::string::npos) << r.stats.planner_config;
  EXPECT_EQ(r.stats.reconfigures, 1u);
  // PIBT has no V: the live value is ignored, not an error.
  FleetManager pibt(g, config("pibt", 2));
  LiveConfig p = pibt.live_config();
  p.V = 5;
  EXPECT_TRUE(pibt.reconfigure(p).empty());
}

TEST(FleetManager, AHeldRobotGetsNoNewMove) {
  const Grid g = warehouse();
  FleetManager fm(g, config("pibt", 2));
  SimFleet sim{fm, {{0, 0}, {11, 4}}};
  sim.step();
  EXPECT_FALSE(fm.set_paused(7, true).empty()) << "an unknown robot is refused";
  EXPECT_TRUE(fm.set_paused(0, true).empty());
  ASSERT_TRUE(fm.submit({0, 2, 11, 0, 0, 0}).accepted);
  ASSERT_TRUE(fm.submit({11, 2, 0, 4, 0, 0}).accepted);
  for (int t = 0; t < 15; ++t) sim.step();
  EXPECT_EQ(sim.xy[0], std::make_pair(0, 0)) << "paused robot 0 stayed";
  EXPECT_NE(sim.xy[1], std::make_pair(11, 4)) << "robot 1 took a task";
  fm.set_emergency_stop(true);
  const auto frozen = sim.xy;
  for (int t = 0; t < 5; ++t) sim.step();
  EXPECT_EQ(sim.xy, frozen) << "nobody moves on emergency stop";
  fm.set_emergency_stop(false);
  EXPECT_TRUE(fm.set_paused(-1, false).empty());
  for (int t = 0; t < 60; ++t) sim.step();
  EXPECT_TRUE(fm.tasks(false).empty()) << "both tasks delivered after the release";
}

TEST(FleetManager, AcceptedTasksSurviveARestartThroughTheJournal) {
  const Grid g = warehouse();
  const std::string path = journal_path();
  FleetConfig c = config("pibt", 2);
  c.task_store = path;
  uint64_t id = 0;
  {
    FleetManager fm(g, c);
    auto r = fm.submit({0, 2, 11, 0, 3, 0});
    ASSERT_TRUE(r.accepted);
    id = r.task_id;
    fm.take_events();  // journaled here
  }
  FleetManager again(g, c);
  const auto open = again.tasks(false);
  ASSERT_EQ(open.size(), 1u);
  EXPECT_EQ(open[0].first, id);
  EXPECT_EQ(open[0].second.priority, 3);
  std::remove(path.c_str());
}

// Hostile reports are ignored with a reason and never move a robot.
TEST(FleetManager, BadRobotReportsAreIgnoredWithAReason) {
  const Grid g = warehouse();
  FleetManager fm(g, config("pibt", 2));
  std::string err;
  RobotReport a;
  a.id = 0, a.x = 0, a.y = 0, a.stamp = 10.0;
  RobotReport b = a;
  b.id = 1, b.x = 11, b.y = 4;
  EXPECT_EQ(fm.update_robots({a, b}, 1.0, err), 0) << err;
  auto expect_ignored = [&](std::vector<RobotReport> reports, const std::string& reason) {
    std::string why;
    EXPECT_EQ(fm.update_robots(reports, 1.0, why), static_cast<int>(reports.size())) << reason;
    EXPECT_NE(why.find(reason), std::string::npos) << why;
  };
  RobotReport moved = a;
  moved.x = 1, moved.stamp = 11.0;
  RobotReport twice = moved;
  twice.x = 0, twice.y = 2;
  expect_ignored({moved, twice}, "twice");
  RobotReport nan = moved;
  nan.pose_finite = false;
  expect_ignored({nan}, "not finite");
  RobotReport stale = moved;
  stale.stamp = 9.0;
  expect_ignored({stale}, "out of order");
  RobotReport off_map = moved;
  off_map.x = 40;
  expect_ignored({off_map}, "off the map");
  RobotReport wall = moved;
  wall.x = 1, wall.y = 1;
  expect_ignored({wall}, "obstacle");
  RobotReport mode = moved;
  mode.mode = 200;
  expect_ignored({mode}, "unknown mode");
  std::vector<RobotReport> flood(100000, a);
  for (size_t i = 0; i < flood.size(); ++i) flood[i].id = 1000 + static_cast<int64_t>(i);
  expect_ignored(flood, "unknown robot id");
  const auto r = fm.tick(2.0, 2.0, true);
  ASSERT_TRUE(r.stepped);
  EXPECT_EQ(r.view.pos[0], g.cell(0, 0)) << "no ignored report moved robot 0";
  std::vector<std::pair<std::string, std::string>> values;
  fm.diagnose(2.0, values);
  std::map<std::string, std::string> d(values.begin(), values.end());
  EXPECT_EQ(d["ignored robot reports"], std::to_string(6 + 100000 + 1));
  EXPECT_NE(d["last ignored robot report"].find("unknown robot id"), std::string::npos);
  EXPECT_EQ(fm.update_robots({moved}, 1.0, err), 0) << "a good, newer report is taken";
}

// Issue 25: a pickup counts only from a cell the execution layer accepted. Robot 0 reports its
// pickup, five cells from where it was (a jump no move explains): the executor does not believe it,
// and the task is not picked (before, the fleet counted the pickup from the report alone). Back
// where it was, it goes to the pickup and picks the load there.
TEST(FleetManager, NoPickupFromAReportTheExecutorRejected) {
  const Grid g = warehouse();
  FleetManager fm(g, config("pibt", 1));
  SimFleet sim{fm, {{0, 0}}};
  const SubmitResult task = fm.submit({5, 0, 11, 4, 0, 0});
  ASSERT_TRUE(task.accepted);
  sim.step();
  auto state = [&] {
    for (auto& [id, t] : fm.tasks(true))
      if (id == task.task_id) return t.state;
    return uint8_t(255);
  };
  EXPECT_EQ(state(), kAssigned);
  const auto before = sim.xy[0];
  std::string err;
  for (int k = 0; k < 3; ++k) {
    sim.now += 0.001;
    ASSERT_TRUE(fm.update_robot(0, 5, 0, false, false, sim.now, err)) << err;
    fm.tick(sim.now, sim.now, false);
    EXPECT_EQ(state(), kAssigned) << "picked from a report the executor rejected";
  }
  sim.xy[0] = before;
  for (int t = 0; t < 20 && state() == kAssigned; ++t) sim.step();
  EXPECT_EQ(state(), kPicked);
}

// Two corridors joined at both ends, and two robots whose manager journals to `path` and waits
// 0.5 s for robots that have not reported after a restart.
namespace {

Grid loop_corridor() { return Grid::from_rows({"........", ".@@@@@@.", "........"}); }

FleetConfig restart_config(const std::string& path) {
  FleetConfig c = config("pibt", 2);
  c.task_store = path;
  c.offline_timeout = 0.5;
  return c;
}

}  // namespace

// Night shift: the planner is killed while robot 1 is on its way from (4,0) into (5,0). The
// successor places it, until it reports, as an obstacle at both cells (the snapshot keeps the cell
// it was commanded into and its heading), and sends robot 0 into neither.
TEST(FleetManager, ARestartedPlannerHoldsTheCellAnUnreportedRobotWasSentInto) {
  const Grid g = loop_corridor();
  const std::string path = journal_path();
  const FleetConfig c = restart_config(path);
  {
    FleetManager before(g, c);
    std::string err;
    ASSERT_TRUE(before.update_robot(0, 0, 0, false, false, 0.0, err));
    ASSERT_TRUE(before.update_robot(1, 4, 0, false, false, 0.0, err));
    ASSERT_TRUE(before.submit({7, 0, 7, 2, 0, 0}).accepted);
    for (int t = 0; t < 3; ++t) before.tick(0.1 * t, 0.1 * t, false);
    bool sent = false;
    for (const auto& cmd : before.tick(0.3, 0.3, false).commands) sent |= cmd.robot == 1 && cmd.cell == g.cell(5, 0);
    ASSERT_TRUE(sent) << "robot 1 is not on its way into (5,0)";
  }  // killed; robot 1 never reports again
  std::vector<std::string> warnings;
  FleetManager after(g, c, [&](LogLevel l, const std::string& m) {
    if (l == LogLevel::kWarn) warnings.push_back(m);
  });
  SimFleet sim{after, {{0, 0}}};
  std::string err;
  for (int t = 0; t < 60; ++t) {
    sim.now += 0.1;
    ASSERT_TRUE(after.update_robot(0, sim.xy[0].first, sim.xy[0].second, false, false, sim.now, err)) << err;
    for (const auto& cmd : after.tick(sim.now, sim.now, false).commands) {
      if (cmd.robot != 0) continue;
      EXPECT_NE(cmd.cell, g.cell(4, 0)) << "tick " << t;
      EXPECT_NE(cmd.cell, g.cell(5, 0)) << "robot 0 sent into the cell robot 1 was entering, tick " << t;
      sim.xy[0] = {g.x_of(cmd.cell), g.y_of(cmd.cell)};
    }
  }
  bool placed = false;
  for (const auto& w : warnings) placed |= w.find("an obstacle at (4,0) and (5,0)") != std::string::npos;
  EXPECT_TRUE(placed) << "robot 1 not placed at both of its cells";
  std::remove(path.c_str());
  std::remove((path + ".robots").c_str());
}

// Night shift: a robot whose reports do not fit (here: the cell another robot stands in) for
// longer than ~offline_timeout gives its task back, which goes to another robot; once its reports
// fit again it takes tasks again. (Before, it kept its task for as long as it stayed so.)
TEST(FleetManager, ARobotWhoseReportsDoNotFitForTooLongGivesItsTaskBack) {
  const Grid g = warehouse();
  FleetConfig c = config("pibt", 2);
  c.offline_timeout = 1.0;
  FleetManager fm(g, c);
  SimFleet sim{fm, {{0, 0}, {11, 4}}};
  sim.step();
  const SubmitResult task = fm.submit({3, 0, 6, 0, 0, 0});
  ASSERT_TRUE(task.accepted);
  sim.step();
  auto owner = [&] {
    for (auto& [id, t] : fm.tasks(true))
      if (id == task.task_id) return t.robot;
    return -2;
  };
  ASSERT_EQ(owner(), 0);
  auto misreport = [&] {  // 0.1 s on: robot 0 reports robot 1's cell, robot 1 its own, a tick
    std::string err;
    sim.now += 0.1;
    ASSERT_TRUE(fm.update_robot(0, 11, 4, false, false, sim.now, err)) << err;
    ASSERT_TRUE(fm.update_robot(1, sim.xy[1].first, sim.xy[1].second, false, false, sim.now, err)) << err;
    fm.tick(sim.now, sim.now, false);
  };
  for (int k = 0; k < 30 && owner() == 0; ++k) {
    misreport();
    if (k < 9) EXPECT_EQ(owner(), 0) << "taken before ~offline_timeout, at report " << k;
  }
  for (int t = 0; t < 3 && owner() != 1; ++t) misreport();
  EXPECT_EQ(owner(), 1) << "the task of a robot whose reports do not fit is not handed on";
  sim.now += 0.1;
  TickResult r = fm.tick(sim.now, sim.now, true);
  ASSERT_EQ(r.view.offline.size(), 2u);
  EXPECT_TRUE(r.view.offline[0]) << "shown as out of service";
  sim.step();  // robot 0 reports where it is again
  r = sim.step(true);
  EXPECT_FALSE(r.view.offline[0]) << "a robot whose reports fit again stays out";
}

// Night shift: the planner is killed while a robot is silent. Its successor must not send the
// others through the cell the silent robot stands in, though that robot never reports again.
TEST(FleetManager, ARestartedPlannerKeepsARobotThatDoesNotReportWhereItWasLastKnown) {
  const Grid g = loop_corridor();
  const std::string path = journal_path();
  const FleetConfig c = restart_config(path);
  {
    FleetManager before(g, c);
    std::string err;
    ASSERT_TRUE(before.update_robot(0, 0, 0, false, false, 0.0, err));
    ASSERT_TRUE(before.update_robot(1, 4, 0, false, false, 0.0, err));
    ASSERT_TRUE(before.tick(0.1, 0.1, false).stepped);
  }  // killed; robot 1 falls silent at (4, 0)
  FleetManager after(g, c);
  ASSERT_TRUE(after.submit({2, 0, 7, 0, 0, 0}).accepted);  // robot 0 must go past (4, 0)
  SimFleet sim{after, {{0, 0}}};
  std::string err;
  std::set<Cell> visited;
  for (int t = 0; t < 80; ++t) {
    sim.now += 0.1;
    ASSERT_TRUE(after.update_robot(0, sim.xy[0].first, sim.xy[0].second, false, false, sim.now, err)) << err;
    const TickResult r = after.tick(sim.now, sim.now, false);
    for (const auto& cmd : r.commands) {
      if (cmd.robot != 0) continue;
      EXPECT_NE(cmd.cell, g.cell(4, 0)) << "robot 0 sent into silent robot 1's cell at tick " << t;
      sim.xy[0] = {g.x_of(cmd.cell), g.y_of(cmd.cell)};
      visited.insert(cmd.cell);
    }
  }
  EXPECT_TRUE(visited.count(g.cell(7, 0))) << "robot 0 went round by the lower corridor";
  EXPECT_TRUE(after.tasks(false).empty()) << "and delivered";
  std::remove(path.c_str());
  std::remove((path + ".robots").c_str());
}

// Turning robots (issue 23): with ~action_model rotation every planner plans with turns; robots
// that make their commands at once (a quarter turn or a forward move per tick) report their
// headings. Every command is one rotation action from the pose the robot reports: a forward move
// only into the cell it faces, a turn in place by a quarter; nobody is sent into another robot's
// cell; robots turn, and tasks are delivered.
TEST(FleetManager, RotationTicksTurnRobotsAndDeliverTasks) {
  const Grid g = warehouse();
  for (const char* planner : {"pibt", "gd-rhcr", "rhcr"}) {
    FleetConfig cfg = config(planner, 4);
    cfg.action_model = "rotation";
    FleetManager fm(g, cfg);
    std::vector<gdrhcr::Pose> pose{{g.cell(0, 0), gdrhcr::kEast}, {g.cell(11, 0), gdrhcr::kSouth},
                                   {g.cell(0, 4), gdrhcr::kNorth}, {g.cell(11, 4), gdrhcr::kWest}};
    for (int k = 0; k < 6; ++k)
      ASSERT_TRUE(fm.submit({k % 12, 2, (11 - 2 * k) % 12, (k % 2) * 4, 0, 0}).accepted) << planner;
    double now = 0;
    int turns = 0, forwards = 0;
    auto report = [&] {
      std::vector<RobotReport> reports;
      for (size_t r = 0; r < pose.size(); ++r) {
        RobotReport rep;
        rep.id = static_cast<int64_t>(r), rep.x = g.x_of(pose[r].cell), rep.y = g.y_of(pose[r].cell);
        rep.heading = pose[r].heading;
        reports.push_back(rep);
      }
      std::string err;
      ASSERT_EQ(fm.update_robots(reports, now, err), 0) << err;
    };
    auto follow = [&](const std::vector<RobotCommand>& commands) {
      for (const RobotCommand& c : commands) {
        const gdrhcr::Pose to{c.cell, c.heading};
        const auto action = gdrhcr::action_between(g, pose[c.robot], to);
        ASSERT_TRUE(action.has_value()) << planner << ": robot " << c.robot << " commanded " << g.describe(c.cell)
                                        << gdrhcr::heading_name(c.heading) << " from " << g.describe(pose[c.robot].cell)
                                        << gdrhcr::heading_name(pose[c.robot].heading);
        EXPECT_EQ(*action, c.action);
        for (size_t o = 0; o < pose.size(); ++o)
          EXPECT_FALSE(o != static_cast<size_t>(c.robot) && pose[o].cell == c.cell) << "sent into robot " << o;
        turns += *action == gdrhcr::Action::kClockwise || *action == gdrhcr::Action::kCounterClockwise;
        forwards += *action == gdrhcr::Action::kForward;
      }
      for (const RobotCommand& c : commands) pose[c.robot] = {c.cell, c.heading};
    };
    uint64_t delivered = 0;
    for (int t = 0; t < 150; ++t) {
      now += 0.001;
      report();
      TickResult r = fm.tick(now, now, t % 10 == 0);
      ASSERT_TRUE(r.stepped) << planner << " tick " << t << ": " << r.skip_reason;
      if (t % 10 == 0) {
        ASSERT_EQ(r.view.heading.size(), 4u);
        for (size_t i = 0; i < 4; ++i) EXPECT_EQ(r.view.heading[i], pose[i].heading);
      }
      follow(r.commands);
      report();
      follow(fm.between_ticks());
      delivered = r.stats.tasks_delivered;
    }
    EXPECT_GT(turns, 0) << planner;
    EXPECT_GT(forwards, 0) << planner;
    EXPECT_GE(delivered, 3u) << planner;
    std::vector<std::pair<std::string, std::string>> diag;
    fm.diagnose(now, diag);
    EXPECT_NE(std::find(diag.begin(), diag.end(), std::make_pair(std::string("action model"), std::string("rotation"))),
              diag.end());
  }
}

// A bad ~action_model stops the manager with an error naming it; in the rotation model a robot
// that reports no heading is ignored with a reason saying so.
TEST(FleetManager, ActionModelIsCheckedAndRotationNeedsHeadings) {
  const Grid g = warehouse();
  FleetConfig bad = config("pibt", 2);
  bad.action_model = "diagonal";
  try {
    FleetManager fm(g, bad);
    FAIL() << "accepted ~action_model diagonal";
  } catch (const gdrhcr::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("~action_model"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("diagonal"), std::string::npos) << e.what();
  }
  FleetConfig cfg = config("pibt", 2);
  cfg.action_model = "rotation";
  FleetManager fm(g, cfg);
  std::string err;
  EXPECT_FALSE(fm.update_robot(0, 0, 0, false, false, 0.1, err));
  EXPECT_NE(err.find("no heading"), std::string::npos) << err;
  RobotReport rep;
  rep.id = 1, rep.heading = 7;
  EXPECT_EQ(fm.update_robots({rep}, 0.1, err), 1);
  EXPECT_NE(err.find("unknown heading"), std::string::npos) << err;
}

// ~prep_file (issue 24 item 2): a preparation made for this map, fleet size and model sets the
// traffic cost of the node's distance table; one made for another map is reported and the node
// runs without it. In the rotation model the aisles are one-way lanes (rule lanes).
TEST(FleetManager, APreparationFileForThisMapSetsTheTrafficCost) {
  const Grid g = warehouse();
  gdrhcr::MapPrep prep;
  prep.map_key = gdrhcr::map_key(g);
  prep.width = g.width(), prep.height = g.height(), prep.agents = 4;
  prep.model = gdrhcr::ActionModel::kRotation;
  prep.planner = "gd-rhcr";
  prep.traffic_cost = 2;
  const std::string path = journal_path() + ".prep.json";
  gdrhcr::save_prep(prep, path);
  FleetConfig c = config("gd-rhcr", 4);
  c.action_model = "rotation";
  c.prep_file = path;
  std::vector<std::string> warnings;
  auto sink = [&](LogLevel level, const std::string& msg) {
    if (level == LogLevel::kWarn) warnings.push_back(msg);
  };
  {
    FleetManager fm(g, c, sink);
    EXPECT_EQ(fm.step_costs().traffic, 2.0);
    EXPECT_EQ(fm.step_costs().lane, 2.0);
    EXPECT_TRUE(warnings.empty());
  }
  prep.map_key = "0123456789abcdef";
  gdrhcr::save_prep(prep, path);
  {
    FleetManager fm(g, c, sink);
    EXPECT_EQ(fm.step_costs().traffic, 0.0);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("was made for another map"), std::string::npos) << warnings[0];
  }
  EXPECT_EQ(FleetManager(g, config("gd-rhcr", 4)).step_costs().lane, 0.0);  // no lanes in mapf
  std::remove(path.c_str());
}
