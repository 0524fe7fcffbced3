// Fleet bookkeeping: task validation, assignment, status transitions, goals, the hold cascade.
#include <gtest/gtest.h>

#include "gd_rhcr_planner/fleet.hpp"
#include "gdrhcr/validator.hpp"

using namespace gd_rhcr_planner;
using gdrhcr::Grid;

namespace {
Grid corridor() {
  return Grid::from_rows({
      "..........",
      ".@@@@@@@@.",
      "..........",
  });
}
std::string report(Fleet& f, int id, int x, int y, bool offline = false) {
  std::string err;
  f.update_robot(id, x, y, offline, false, err);
  return err;
}
}  // namespace

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
