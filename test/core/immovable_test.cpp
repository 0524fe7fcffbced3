// Immovable agents (robots gone offline): every planner keeps them in place, never moves
// another agent into their cell, and, given distances that route around them
// (DistTable with blocked cells), gets the others past them to their goals. Blocked cells
// (WorldView::blocked: a late robot is still leaving them, no agent stands on them) and agents
// immovable for a while (late robots in the ROS node's execution layer): no planner moves an
// agent into a blocked cell, the planners that look ahead route around it, and an agent that is
// free again is planned again instead of following the plan that only kept it in place.
#include <gtest/gtest.h>

#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/local_guidance.hpp"
#include "gdrhcr/pbs.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {

// A 2-lane corridor with a pocket: the offline robot sits in the lower lane, the traffic must
// switch lanes to pass it.
Grid corridor() {
  return Grid::from_rows({
      "@@@@@@@@@@@@",
      "............",
      "............",
      "@@@@@@@@@@@@",
  });
}

std::unique_ptr<Planner> build(const std::string& name, const Grid& g, int n) {
  Params p;
  if (name == "guided-pibt") {
    p.set("guidance", "local");
    return make_planner("pibt", p, g, n, 3);
  }
  if (name != "pibt") p.set("node-budget", "2000");
  if (name == "rhcr") p.set("alpha", "2"), p.set("H", "8");
  if (name == "gd-rhcr") p.set("H", "8");
  return make_planner(name, p, g, n, 3);
}

class ImmovableAgents : public ::testing::TestWithParam<std::string> {};
class BlockedCells : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(ImmovableAgents, OthersPassAnOfflineRobotWithoutTouchingIt) {
  const Grid g = corridor();
  const Cell offline_cell = g.cell(6, 2);
  DistTable dist(g, std::vector<Cell>{offline_cell});
  // Agent 0 offline in the middle of the lower lane; agents 1, 2 travel along the lower lane
  // through its cell's column (both directions); agent 3 along the upper lane.
  std::vector<Cell> pos = {offline_cell, g.cell(0, 2), g.cell(11, 2), g.cell(0, 1)};
  const std::vector<std::vector<Cell>> goals = {
      {offline_cell}, {g.cell(11, 2)}, {g.cell(1, 2)}, {g.cell(11, 1)}};
  std::vector<uint8_t> immovable = {1, 0, 0, 0};
  auto planner = build(GetParam(), g, 4);
  StepValidator validator(g);
  std::vector<bool> reached(4, false);
  for (int t = 0; t < 60; ++t) {
    WorldView w{g, dist, t, pos, goals};
    w.immovable = &immovable;
    std::vector<Cell> next(pos);
    planner->plan_step(w, next);
    ASSERT_FALSE(validator.check(pos, next)) << GetParam() << " t=" << t;
    ASSERT_EQ(next[0], offline_cell) << GetParam() << ": the offline robot was moved at t=" << t;
    pos = next;
    for (int i = 1; i < 4; ++i) reached[i] = reached[i] || pos[i] == goals[i][0];
  }
  EXPECT_TRUE(reached[1] && reached[2] && reached[3])
      << GetParam() << ": " << reached[1] << reached[2] << reached[3];
}

TEST_P(ImmovableAgents, ARobotGoingOfflineMidPlanIsRoutedAround) {
  // Plans are made while agent 0 moves; then it stops for good in the lower lane. The others'
  // cached plans that run through its cell must be dropped, not followed into it.
  const Grid g = corridor();
  DistTable free_dist(g);
  std::vector<Cell> pos = {g.cell(5, 2), g.cell(0, 2), g.cell(11, 1)};
  const std::vector<std::vector<Cell>> goals = {{g.cell(7, 2)}, {g.cell(11, 2)}, {g.cell(0, 1)}};
  std::vector<uint8_t> immovable(3, 0);
  auto planner = build(GetParam(), g, 3);
  StepValidator validator(g);
  std::unique_ptr<DistTable> blocked_dist;
  bool reached1 = false;
  Cell stopped = kNoCell;
  for (int t = 0; t < 60; ++t) {
    if (t == 1) {  // agent 0 stops where it is now
      immovable[0] = 1;
      stopped = pos[0];
      blocked_dist = std::make_unique<DistTable>(g, std::vector<Cell>{stopped});
    }
    std::vector<std::vector<Cell>> g_now = goals;
    if (immovable[0]) g_now[0] = {pos[0]};
    WorldView w{g, blocked_dist ? *blocked_dist : free_dist, t, pos, g_now};
    w.immovable = &immovable;
    std::vector<Cell> next(pos);
    planner->plan_step(w, next);
    ASSERT_FALSE(validator.check(pos, next)) << GetParam() << " t=" << t;
    if (immovable[0]) ASSERT_EQ(next[0], stopped) << GetParam() << " t=" << t;
    pos = next;
    reached1 = reached1 || pos[1] == goals[1][0];
  }
  EXPECT_TRUE(reached1) << GetParam() << ": agent 1 never got past the stopped robot";
}

INSTANTIATE_TEST_SUITE_P(Planners, ImmovableAgents, ::testing::Values("pibt", "rhcr", "gd-rhcr"));

TEST(DistTableBlocked, RoutesAroundBlockedCellsAndAcceptsAGoalOnOne) {
  const Grid g = corridor();
  const Cell b = g.cell(6, 2);
  DistTable dist(g, std::vector<Cell>{b});
  EXPECT_EQ(dist.get(g.cell(7, 2), g.cell(5, 2)), 4);  // up, across two, down
  EXPECT_GE(dist.get(g.cell(7, 2), b), kUnreachable);   // nobody reaches the blocked cell
  EXPECT_EQ(dist.get(b, b), 0);                           // but it may be a goal (its robot's)
  EXPECT_EQ(dist.get(b, g.cell(5, 2)), 1);
}

TEST(PbsBlocked, NoPathUsesABlockedCell) {
  const Grid g = corridor();
  const std::vector<Cell> blocked = {g.cell(6, 2)};
  DistTable dist(g, blocked);
  PbsConfig pc;
  pc.horizon = 12;
  pc.blocked_cells = &blocked;
  auto r = solve_pbs(g, dist, {g.cell(0, 2), g.cell(11, 2)}, {{g.cell(11, 2)}, {g.cell(0, 2)}}, nullptr, pc);
  ASSERT_TRUE(r.success);
  for (auto& path : r.paths)
    for (Cell c : path) EXPECT_NE(c, blocked[0]);
}

TEST_P(BlockedCells, NobodyEntersOneAndLookaheadPlannersGoAround) {
  const Grid g = corridor();
  DistTable dist(g);  // plain distances: a blocked cell is not in the table
  const std::vector<Cell> blocked = {g.cell(6, 2)};
  // Agent 0 along the lower lane through the blocked cell; agent 1 the other way on the upper lane.
  std::vector<Cell> pos = {g.cell(1, 2), g.cell(10, 1)};
  const std::vector<std::vector<Cell>> goals = {{g.cell(11, 2)}, {g.cell(0, 1)}};
  auto planner = build(GetParam(), g, 2);
  StepValidator validator(g);
  bool reached = false;
  for (int t = 0; t < 40; ++t) {
    WorldView w{g, dist, t, pos, goals};
    w.blocked = &blocked;
    std::vector<Cell> next(pos);
    planner->plan_step(w, next);
    ASSERT_FALSE(validator.check(pos, next)) << GetParam() << " t=" << t;
    for (Cell c : next) ASSERT_NE(c, blocked[0]) << GetParam() << ": an agent entered the blocked cell at t=" << t;
    pos = next;
    reached = reached || pos[0] == goals[0][0];
  }
  // Plain PIBT only looks one step ahead (it waits before the cell); the others detour.
  if (GetParam() != "pibt") EXPECT_TRUE(reached) << GetParam() << ": never got past the blocked cell";
}

INSTANTIATE_TEST_SUITE_P(Planners, BlockedCells, ::testing::Values("pibt", "guided-pibt", "rhcr", "gd-rhcr"),
                         [](const auto& info) {
                           std::string s = info.param;
                           for (char& c : s)
                             if (c == '-') c = '_';
                           return s;
                         });

TEST(BlockedCellGuidance, CountsABlockedCellAsTaken) {
  const Grid g = corridor();
  DistTable dist(g);
  const std::vector<Cell> pos = {g.cell(4, 2)};
  const std::vector<std::vector<Cell>> goals = {{g.cell(9, 2)}};
  const std::vector<Cell> blocked = {g.cell(6, 2)};
  LocalGuidanceConfig cfg;
  cfg.window = 10;
  auto path_with = [&](const std::vector<Cell>* b) {
    LocalGuidance lg(g, 1, cfg);
    WorldView w{g, dist, 0, pos, goals};
    w.blocked = b;
    lg.update(w, {0});
    return lg.path_from(0, 0);
  };
  const auto free_path = path_with(nullptr);
  EXPECT_NE(std::find(free_path.begin(), free_path.end(), blocked[0]), free_path.end())
      << "the shortest path runs through the cell";
  const auto path = path_with(&blocked);
  ASSERT_FALSE(path.empty());
  EXPECT_EQ(path.back(), goals[0][0]);
  EXPECT_EQ(std::find(path.begin(), path.end(), blocked[0]), path.end()) << "the guidance ran through the blocked cell";
}

// An immovable agent (a robot still making its committed moves, an offline one) stays where it
// is for the guidance too: it gets no search of its own (which would have it move on towards its
// goal and free its cell for the others' guidance), and the others go around it.
TEST(BlockedCellGuidance, AnImmovableAgentStaysInTheOthersGuidance) {
  const Grid g = corridor();
  DistTable dist(g);
  const std::vector<Cell> pos = {g.cell(6, 2), g.cell(4, 2)};
  const std::vector<std::vector<Cell>> goals = {{g.cell(11, 2)}, {g.cell(9, 2)}};
  const std::vector<uint8_t> immovable = {1, 0};
  LocalGuidanceConfig cfg;
  cfg.window = 10;
  LocalGuidance lg(g, 2, cfg);
  WorldView w{g, dist, 0, pos, goals, &immovable};
  lg.update(w, {0, 1});
  EXPECT_EQ(lg.next_cell(0, 0, pos[0]), pos[0]) << "the immovable agent's guidance moves it";
  const auto path = lg.path_from(1, 0);
  ASSERT_FALSE(path.empty());
  EXPECT_EQ(path.back(), goals[1][0]);
  EXPECT_EQ(std::find(path.begin(), path.end(), pos[0]), path.end()) << "the guidance ran through the immovable agent";
}

// A plan made while an agent was immovable only keeps it in place; once it is free again (a late
// robot arrived) it must be planned again, not kept there until that plan runs out. (GD-RHCR
// reused such a plan for up to H steps: every delay of a robot froze it for the whole window.)
TEST(ImmovableForAWhile, AnAgentFreeAgainIsNotHeldByItsOldPlan) {
  const Grid g = corridor();
  DistTable dist(g);
  Params p;
  p.set("node-budget", "2000");
  p.set("H", "8");
  p.set("max-density", "1");  // a corridor is crowded for the density rule: keep PBS and its cached plans
  auto planner = make_planner("gd-rhcr", p, g, 2, 3);
  std::vector<Cell> pos = {g.cell(0, 2), g.cell(11, 1)};
  const std::vector<std::vector<Cell>> goals = {{g.cell(11, 2)}, {g.cell(0, 1)}};
  std::vector<uint8_t> immovable = {1, 0};
  for (int t = 0; t < 3; ++t) {
    if (t == 1) immovable[0] = 0;  // its delay is over
    WorldView w{g, dist, t, pos, goals};
    w.immovable = &immovable;
    std::vector<Cell> next(pos);
    planner->plan_step(w, next);
    if (t == 0) ASSERT_EQ(next[0], pos[0]);
    else EXPECT_NE(next[0], pos[0]) << "t=" << t << ": agent 0 is free and alone in its lane, yet it waits";
    pos = next;
  }
}
