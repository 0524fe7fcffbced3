// Mapf steps executed in the rotation model (mapf_in_rotation.hpp): the conversion keeps every
// step valid (followers of a turning agent wait, cycles move or stop as one), and a wrapped
// planner runs a whole simulation in the rotation model, validated step by step.
#include <gtest/gtest.h>

#include "gdrhcr/mapf_in_rotation.hpp"
#include "gdrhcr/params.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

TEST(MapfInRotation, WhoeverFollowsAnAgentThatTurnsWaits) {
  Grid g = Grid::from_rows({"......", "......"});
  // A train along row 0 heading east: 0 at (0,0), 1 at (1,0), 2 at (2,0); the front one (2)
  // faces north but wants to go east, so it turns (clockwise from north) and 1 and 0 wait.
  const std::vector<Cell> pos{g.cell(0, 0), g.cell(1, 0), g.cell(2, 0), g.cell(5, 0)};
  const std::vector<Cell> next{g.cell(1, 0), g.cell(2, 0), g.cell(3, 0), g.cell(5, 1)};
  const std::vector<Heading> heading{kEast, kEast, kNorth, kSouth};
  using A = Action;
  const auto act = rotation_actions_for_step(g, pos, heading, next);
  EXPECT_EQ(act, (std::vector<A>{A::kWait, A::kWait, A::kClockwise, A::kForward}));
  // Facing away (west, wants east): a half turn, clockwise first; facing south: counter-clockwise.
  EXPECT_EQ(rotation_actions_for_step(g, {g.cell(5, 0)}, {kWest}, {g.cell(4, 0)})[0], A::kForward);
  EXPECT_EQ(rotation_actions_for_step(g, {g.cell(0, 0)}, {kWest}, {g.cell(1, 0)})[0], A::kClockwise);
  EXPECT_EQ(rotation_actions_for_step(g, {g.cell(0, 0)}, {kSouth}, {g.cell(1, 0)})[0], A::kCounterClockwise);
  // A rotating cycle of four, all facing their next cell, moves as one.
  const std::vector<Cell> cyc{g.cell(0, 0), g.cell(1, 0), g.cell(1, 1), g.cell(0, 1)};
  const std::vector<Cell> cyc_next{g.cell(1, 0), g.cell(1, 1), g.cell(0, 1), g.cell(0, 0)};
  EXPECT_EQ(rotation_actions_for_step(g, cyc, {kEast, kSouth, kWest, kNorth}, cyc_next), std::vector<A>(4, A::kForward));
  // One of them turning stops the whole cycle.
  EXPECT_EQ(rotation_actions_for_step(g, cyc, {kEast, kSouth, kWest, kWest}, cyc_next),
            (std::vector<A>{A::kWait, A::kWait, A::kWait, A::kClockwise}));
  EXPECT_THROW(rotation_actions_for_step(g, {g.cell(0, 0)}, {kEast}, {g.cell(2, 0)}), std::logic_error);
}

TEST(MapfInRotation, APlannersStepsStayValidStepAfterStep) {
  // PIBT on warehouse-10-20-10-2-1 with 150 agents for 150 steps, its steps executed as MAPF_T
  // actions: every executed step is valid, agents only move along their heading, and they
  // still deliver (turning costs time, it does not stop them).
  Grid w = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/warehouse-10-20-10-2-1.map");
  DistTable dist(w);
  Params params;
  const int n = 150;
  auto planner = make_planner("pibt", params, w, n, 1);
  RandomNavigationStream tasks(w, 2);
  std::vector<Cell> pos = random_starts(w, n, 5), next(n);
  std::vector<Heading> heading(n);
  for (int i = 0; i < n; ++i) heading[i] = static_cast<Heading>(i % 4);
  std::vector<std::vector<Cell>> goals(n);
  for (int i = 0; i < n; ++i) goals[i] = {tasks.next_goal(i, pos[i])};
  StepValidator validator(w, ActionModel::kRotation);
  long reached = 0, forward = 0;
  for (int t = 0; t < 150; ++t) {
    std::fill(next.begin(), next.end(), kNoCell);
    planner->plan_step(WorldView{w, dist, t, pos, goals}, next);
    const auto act = rotation_actions_for_step(w, pos, heading, next);
    std::vector<Cell> moved = pos;
    std::vector<Heading> turned = heading;
    for (int i = 0; i < n; ++i) {
      const Pose p = apply_action(w, Pose{pos[i], heading[i]}, act[i]);
      moved[i] = p.cell, turned[i] = p.heading;
      ASSERT_TRUE(moved[i] == pos[i] || moved[i] == next[i]) << "agent " << i << " left its planned cell";
      forward += moved[i] != pos[i];
    }
    ASSERT_NO_THROW(validator.require_valid(pos, moved, t, &heading, &turned));
    pos = moved;
    heading = turned;
    for (int i = 0; i < n; ++i)
      if (pos[i] == goals[i][0]) ++reached, goals[i][0] = tasks.next_goal(i, pos[i]);
  }
  EXPECT_GT(forward, 150 * 20);
  EXPECT_GT(reached, 30);
}

TEST(MapfInRotation, WrappedPlannersRunTheRotationModelWithoutCollisions) {
  // Every planner, its mapf steps executed with turns, on warehouse-10-20-10-2-1 with 100 agents:
  // the simulator validates each step in the rotation model (a violation throws), goals are
  // reached, and turns happen.
  Grid w = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/warehouse-10-20-10-2-1.map");
  DistTable dist(w, ActionModel::kRotation);
  for (const std::string name : {"pibt", "rhcr", "gd-rhcr"}) {
    Params params;
    const PlannerParams values = PlannerParams::resolve(name, params, MapFacts(w, 100));
    MapfInRotation planner(make_planner(values, w, 100, 1), w);
    RandomNavigationStream tasks(w, 1);
    SimOptions opt;
    opt.steps = 120;
    opt.action_model = ActionModel::kRotation;
    const SimResult r = run_simulation(w, dist, tasks, planner, random_starts(w, 100, 1), opt);
    EXPECT_GT(r.goals_reached, 40) << name;
    const auto stats = planner.stats();
    EXPECT_EQ(stats["rotation_by"], "mapf-wait");
    EXPECT_GT(stats["rotation_turns"].get<long>(), 100) << name;
    EXPECT_GT(stats["rotation_forward_moves"].get<long>(), 100 * 30) << name;
  }
  // A mapf world is refused, naming the planner.
  Params params;
  MapfInRotation pibt(make_planner("pibt", params, w, 1, 1), w);
  DistTable mapf_dist(w);
  const std::vector<Cell> pos{w.free_cells()[0]};
  const std::vector<std::vector<Cell>> goals{{w.free_cells()[1]}};
  std::vector<Cell> next(1);
  try {
    pibt.plan_step(WorldView{w, mapf_dist, 0, pos, goals}, next);
    ADD_FAILURE() << "a mapf world was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("pibt"), std::string::npos) << e.what();
  }
}
