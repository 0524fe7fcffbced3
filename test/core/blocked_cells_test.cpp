// Blocked cells (WorldView::blocked: a late robot is still leaving them, no agent stands on them)
// and agents that are immovable for a while (late robots in the ROS node's execution layer):
// no planner moves an agent into a blocked cell, the planners that look ahead route around it,
// and an agent that is free again is planned again instead of following the plan that only kept
// it in place.
#include <gtest/gtest.h>

#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/local_guidance.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {

// A 2-lane corridor: the blocked cell is in the lower lane, traffic along it must switch lanes.
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

class BlockedCells : public ::testing::TestWithParam<std::string> {};

}  // namespace

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
