// Distinct goals (distinct_goal_stream.hpp): no agent is handed a goal another agent holds.
#include <gtest/gtest.h>

#include <set>

#include "gdrhcr/distinct_goal_stream.hpp"
#include "gdrhcr/guided_pibt.hpp"
#include "gdrhcr/simulator.hpp"

using namespace gdrhcr;

TEST(DistinctGoalStream, NeverHandsOutAnotherAgentsGoal) {
  // A small map and many agents: a plain draw would often repeat another agent's goal.
  Grid g = Grid::from_rows({"......", "......", "......"});
  const int n = 10;
  DistinctGoalStream tasks(std::make_unique<RandomNavigationStream>(g, 3));
  std::vector<Cell> goal(n, kNoCell);
  for (int i = 0; i < n; ++i) goal[i] = tasks.next_goal(i, g.cell(i % 6, i / 6));
  for (int round = 0; round < 200; ++round) {
    const int i = round % n;
    goal[i] = tasks.next_goal(i, goal[i]);  // reached it: the next one
    std::set<Cell> distinct(goal.begin(), goal.end());
    ASSERT_EQ(distinct.size(), goal.size()) << "round " << round;
  }
  EXPECT_GT(tasks.redraws(), 0);
}

TEST(DistinctGoalStream, SimulationRunsWithIt) {
  Grid g = Grid::from_rows({"........", "..@@....", "........"});
  DistTable dist(g);
  DistinctGoalStream tasks(std::make_unique<RandomNavigationStream>(g, 2));
  PibtPlanner p(g, 6, 2);
  SimOptions opt;
  opt.steps = 100;
  opt.lookahead = 1;
  SimResult r = run_simulation(g, dist, tasks, p, random_starts(g, 6, 2), opt);
  EXPECT_GT(r.goals_reached, 0);
}
