// Fleet bookkeeping: task validation, assignment, status transitions, goals, the hold cascade.
#include <gtest/gtest.h>

#include "fleet_fixtures.hpp"
#include "gd_rhcr_planner/fleet.hpp"
#include "gdrhcr/validator.hpp"

using namespace gd_rhcr_planner;
using namespace gd_rhcr_planner::fixtures;
using gdrhcr::Grid;

TEST(Fleet, RejectsBadTasksWithReasons) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  Fleet f(g, d, 2);
  auto r = f.submit(1, 1, 0, 0, 0);
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.reason.find("obstacle"), std::string::npos) << r.reason;
  ASSERT_NE(f.task(r.task_id), nullptr);
  EXPECT_EQ(f.task(r.task_id)->state, kFailed);
  r = f.submit(0, 0, 50, 0, 0);
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.reason.find("off the map"), std::string::npos) << r.reason;
  r = f.submit(0, 0, 0, 0, 0);
  EXPECT_FALSE(r.accepted);
  r = f.submit(0, 0, 9, 2, 0, 77);
  EXPECT_TRUE(r.accepted);
  EXPECT_EQ(r.task_id, 77u);
  r = f.submit(0, 0, 9, 2, 0, 77);
  EXPECT_FALSE(r.accepted);
  EXPECT_NE(r.reason.find("already"), std::string::npos);
  auto events = f.take_events();
  ASSERT_EQ(events.size(), 4u);  // three failures, one queued
  EXPECT_EQ(events[3].state, kQueued);
  EXPECT_EQ(f.failed_total(), 3u);
}

TEST(Fleet, UnknownRobotAndBadCellAreIgnored) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  Fleet f(g, d, 2);
  EXPECT_NE(report(f, 5, 0, 0).find("unknown robot"), std::string::npos);
  EXPECT_NE(report(f, -1, 0, 0).find("unknown robot"), std::string::npos);
  EXPECT_NE(report(f, 0, 1, 1).find("obstacle"), std::string::npos);
  EXPECT_FALSE(f.all_reported());
  EXPECT_EQ(report(f, 0, 0, 0), "");
  EXPECT_EQ(report(f, 1, 0, 0), "");
  EXPECT_NE(f.position_conflict(), "");
  EXPECT_EQ(report(f, 1, 9, 0), "");
  EXPECT_TRUE(f.all_reported());
  EXPECT_EQ(f.position_conflict(), "");
}

// Issue 25: the cell a moving robot reports entering is checked like its cell: on the map, free,
// and one move from where it is; otherwise the report is ignored with the reason.
TEST(Fleet, TheCellARobotReportsEnteringIsChecked) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  Fleet f(g, d, 2);
  std::string err;
  EXPECT_FALSE(f.update_robot(0, 0, 0, false, true, err, 1.0, std::make_pair(-1, 0)));
  EXPECT_NE(err.find("entering cell (-1,0) is off the map"), std::string::npos) << err;
  EXPECT_FALSE(f.update_robot(0, 0, 0, false, true, err, 1.0, std::make_pair(2, 0)));
  EXPECT_NE(err.find("is not next to its cell"), std::string::npos) << err;
  EXPECT_FALSE(f.update_robot(0, 0, 0, false, true, err, 1.0, std::make_pair(0, 0)));
  EXPECT_NE(err.find("is not next to its cell"), std::string::npos) << err;
  EXPECT_FALSE(f.robot(0).reported) << "a rejected report is not taken";
  ASSERT_TRUE(f.update_robot(0, 0, 0, false, true, err, 1.0, std::make_pair(1, 0))) << err;
  EXPECT_EQ(f.robot(0).entering, g.cell(1, 0));
  ASSERT_TRUE(f.update_robot(0, 1, 0, false, false, err, 2.0, std::make_pair(2, 0))) << err;
  EXPECT_EQ(f.robot(0).entering, gdrhcr::kNoCell) << "a robot at rest enters nothing";
}

TEST(Fleet, NearestIdleRobotAndLifecycle) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  Fleet f(g, d, 2);
  report(f, 0, 0, 0);
  report(f, 1, 9, 0);
  auto low = f.submit(8, 0, 0, 2, 0);
  auto high = f.submit(1, 0, 9, 2, 5);
  f.advance();
  EXPECT_EQ(f.task(high.task_id)->robot, 0);  // higher priority first, nearest robot
  EXPECT_EQ(f.task(low.task_id)->robot, 1);
  EXPECT_EQ(f.mode(0), kToPickup);
  std::vector<std::vector<gdrhcr::Cell>> goals;
  f.fill_goals(goals);
  ASSERT_EQ(goals[0].size(), 2u);
  EXPECT_EQ(goals[0][0], g.cell(1, 0));
  EXPECT_EQ(goals[0][1], g.cell(9, 2));
  EXPECT_EQ(f.distance_left(high.task_id), 1 + 10);
  report(f, 0, 1, 0);
  f.advance();
  EXPECT_EQ(f.task(high.task_id)->state, kPicked);
  EXPECT_EQ(f.mode(0), kToDelivery);
  f.fill_goals(goals);
  ASSERT_EQ(goals[0].size(), 1u);
  report(f, 0, 9, 2);
  f.advance();
  EXPECT_EQ(f.task(high.task_id)->state, kDelivered);
  EXPECT_EQ(f.mode(0), kIdle);
  EXPECT_EQ(f.delivered_total(), 1u);
  f.fill_goals(goals);
  EXPECT_EQ(goals[0], std::vector<gdrhcr::Cell>{g.cell(9, 2)});  // idle: stay
  std::vector<uint8_t> states;
  for (auto& e : f.take_events())
    if (e.task_id == high.task_id) states.push_back(e.state);
  EXPECT_EQ(states, (std::vector<uint8_t>{kQueued, kAssigned, kPicked, kDelivered}));
}

TEST(Fleet, CancelAndOffline) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  Fleet f(g, d, 2);
  report(f, 0, 0, 0);
  report(f, 1, 9, 0);
  auto a = f.submit(5, 0, 0, 2, 0);
  auto b = f.submit(5, 2, 9, 2, 0);
  f.advance();
  std::string reason;
  EXPECT_TRUE(f.cancel(a.task_id, reason));
  EXPECT_FALSE(f.cancel(a.task_id, reason));
  EXPECT_NE(reason.find("already cancelled"), std::string::npos);
  EXPECT_FALSE(f.cancel(12345, reason));
  // The robot holding b goes offline before the pickup: b is requeued to the other robot.
  const int holder = f.task(b.task_id)->robot;
  ASSERT_GE(holder, 0);
  report(f, holder, holder == 0 ? 0 : 9, 0, /*offline=*/true);
  f.advance();
  EXPECT_EQ(f.mode(holder), kOffline);
  EXPECT_EQ(f.task(b.task_id)->state, kAssigned);
  EXPECT_EQ(f.task(b.task_id)->robot, 1 - holder);
}

TEST(HoldCascade, HoldsTheChainBehindAStoppedRobot) {
  Grid g = corridor();
  // Robots 0,1,2 in a row on the top corridor moving right; robot 2 is held.
  std::vector<gdrhcr::Cell> pos = {g.cell(0, 0), g.cell(1, 0), g.cell(2, 0), g.cell(0, 2)};
  std::vector<gdrhcr::Cell> next = {g.cell(1, 0), g.cell(2, 0), g.cell(3, 0), g.cell(1, 2)};
  std::vector<uint8_t> held = {0, 0, 1, 0};
  EXPECT_EQ(hold_cascade(g, pos, next, held), 3);
  EXPECT_EQ(next[0], pos[0]);
  EXPECT_EQ(next[1], pos[1]);
  EXPECT_EQ(next[2], pos[2]);
  EXPECT_EQ(next[3], g.cell(1, 2));  // unrelated robot keeps moving
  gdrhcr::StepValidator v(g);
  EXPECT_FALSE(v.check(pos, next).has_value());
}

TEST(Fleet, SilentRobotGoesOfflineAfterTheTimeoutAndItsLoadIsRequeued) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  Fleet f(g, d, 2);
  std::string err;
  ASSERT_TRUE(f.update_robot(0, 5, 0, false, false, err, 10.0));  // on the pickup
  ASSERT_TRUE(f.update_robot(1, 9, 2, false, false, err, 10.0));
  const auto t = f.submit(5, 0, 0, 2, 0).task_id;
  f.advance();
  ASSERT_EQ(f.task(t)->state, kPicked);
  ASSERT_EQ(f.task(t)->robot, 0);
  ASSERT_TRUE(f.update_robot(0, 4, 0, false, false, err, 10.0));  // one step off the pickup
  // Robot 1 keeps reporting, robot 0 falls silent.
  ASSERT_TRUE(f.update_robot(1, 9, 2, false, false, err, 11.5));
  EXPECT_TRUE(f.mark_silent(12.0, 2.0).empty());  // 2 s without a report: not yet
  EXPECT_EQ(f.mark_silent(12.5, 2.0), std::vector<int>{0});
  EXPECT_TRUE(f.mark_silent(13.0, 2.0).empty());  // reported once
  EXPECT_EQ(f.mode(0), kOffline);
  EXPECT_EQ(f.command_mode(0), kToDelivery);  // never commanded "offline" (it would echo it)
  EXPECT_EQ(f.offline_count(), 1);
  f.advance();
  EXPECT_EQ(f.command_mode(0), kIdle);  // its load requeued
  // Requeued and given to the other robot, which fetches the load from the pickup again.
  EXPECT_EQ(f.task(t)->state, kAssigned);
  EXPECT_EQ(f.task(t)->robot, 1);
  bool requeued = false;
  for (auto& e : f.take_events())
    if (e.task_id == t && e.state == kQueued && e.reason.find("stopped reporting carrying the load") != std::string::npos)
      requeued = true;
  EXPECT_TRUE(requeued);
  std::vector<gdrhcr::Cell> pos;
  f.fill_positions(pos);
  EXPECT_EQ(pos[0], g.cell(4, 0));  // an obstacle where it was last seen
  // A report brings it back, idle.
  ASSERT_TRUE(f.update_robot(0, 4, 0, false, false, err, 20.0));
  EXPECT_EQ(f.mode(0), kIdle);
  EXPECT_EQ(f.offline_count(), 0);
}

TEST(HoldCascade, BlockedCellsHoldTheRobotsEnteringThemAndTheirChain) {
  Grid g = corridor();
  // A silent robot may be moving into (3,0): robot 1 planned to enter it, robot 0 follows robot 1.
  std::vector<gdrhcr::Cell> pos = {g.cell(1, 0), g.cell(2, 0), g.cell(5, 2)};
  std::vector<gdrhcr::Cell> next = {g.cell(2, 0), g.cell(3, 0), g.cell(6, 2)};
  std::vector<uint8_t> held(3, 0);
  EXPECT_EQ(hold_cascade(g, pos, next, held, {g.cell(3, 0)}), 2);
  EXPECT_EQ(next[0], pos[0]);
  EXPECT_EQ(next[1], pos[1]);
  EXPECT_EQ(next[2], g.cell(6, 2));
}

TEST(Fleet, TasksUnderAnOfflineRobotWaitInTheQueue) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  Fleet f(g, d, 3);
  report(f, 0, 0, 0);
  report(f, 1, 9, 0);
  report(f, 2, 9, 2);
  const auto t = f.submit(5, 0, 0, 2, 0).task_id;
  f.advance();
  const int holder = f.task(t)->robot;
  ASSERT_GE(holder, 0);
  // Robot 2 dies on the pickup cell: the task goes back to the queue and is not handed out.
  std::string err;
  ASSERT_TRUE(f.update_robot(2, 5, 0, true, false, err));
  f.advance();
  EXPECT_EQ(f.task(t)->state, kQueued);
  EXPECT_NE(f.task(t)->reason.find("blocked by offline robot 2"), std::string::npos) << f.task(t)->reason;
  f.advance();
  EXPECT_EQ(f.task(t)->state, kQueued);
  const auto other = f.submit(9, 2, 0, 2, 0).task_id;  // unaffected tasks still go out
  f.advance();
  EXPECT_EQ(f.task(other)->state, kAssigned);
  // It leaves: the task is assigned again.
  ASSERT_TRUE(f.update_robot(2, 6, 0, false, false, err));
  f.advance();
  EXPECT_EQ(f.task(t)->state, kAssigned);
}
