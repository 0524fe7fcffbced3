// Motion forecast (motion_forecast.hpp): guided PIBT rolled forward, whose cells the next
// guidance update plans around. The forecast itself must be a collision-free rollout from the
// decided step; the solvers using it must stay collision-free (the simulator validates every
// executed step), reach goals in a corridor and on a map that is not biconnected, and be
// deterministic.
#include <algorithm>

#include <gtest/gtest.h>

#include "solver_scenarios.hpp"

#include "gdrhcr/gd_rhcr.hpp"
#include "preset_config.hpp"
#include "gdrhcr/motion_forecast.hpp"
#include "gdrhcr/guided_pibt.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/task_stream.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

using gdrhcr::test_support::ListStream;
using gdrhcr::test_support::run;

MotionForecastConfig forecast(int steps) {
  MotionForecastConfig f;
  f.steps = steps;
  return f;
}

GdRhcrConfig product_with_forecast() {
  GdRhcrConfig c = preset_config("default");
  c.forecast = forecast(10);
  c.node_budget = 200;
  c.timeout_s = 1e6;
  return c;
}
}  // namespace

TEST(MotionForecast, IsACollisionFreeRolloutFromTheDecidedStep) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist(g);
  const int n = 200;
  std::vector<Cell> pos = random_starts(g, n, 3);
  RandomNavigationStream tasks(g, 3);
  std::vector<std::vector<Cell>> goals(n);
  for (int i = 0; i < n; ++i) goals[i] = {tasks.next_goal(i, pos[i])};
  LocalGuidanceConfig lg;
  LocalGuidance guidance(g, n, lg);
  PibtStep pibt(g, n, 3);
  MotionForecast f(g, n, forecast(8), lg);
  std::vector<int> all(n);
  for (int i = 0; i < n; ++i) all[i] = i;
  WorldView w{g, dist, 0, pos, goals};
  guidance.update(w, all);
  std::vector<Cell> preferred(n), next(n, kNoCell);
  for (int i = 0; i < n; ++i) preferred[i] = guidance.next_cell(i, 0, pos[i]);
  pibt.step(w, next, {}, {}, &preferred);
  const double priority_before = pibt.priority(0);
  f.roll(w, next, all, pibt, guidance);
  EXPECT_EQ(pibt.priority(0), priority_before);  // the real PIBT is not advanced
  StepValidator check(g);
  for (int k = 0; k + 1 < 8; ++k) {
    std::vector<Cell> a(n), b(n);
    for (int i = 0; i < n; ++i) {
      ASSERT_EQ(f.forecast(i).size(), 8u);
      a[i] = f.forecast(i)[k], b[i] = f.forecast(i)[k + 1];
    }
    if (k == 0) EXPECT_EQ(a, next);
    EXPECT_FALSE(check.check(a, b).has_value()) << "rollout step " << k;
  }
}

TEST(MotionForecast, SeedsOnlyAgentsOnTheirForecastWithTheSameGoalThatMove) {
  Grid g = Grid::from_rows({"..........", "..........", ".........."});
  DistTable dist(g);
  std::vector<Cell> pos = {g.cell(0, 0), g.cell(0, 2), g.cell(5, 1)};
  std::vector<std::vector<Cell>> goals = {{g.cell(9, 0)}, {g.cell(9, 2)}, {g.cell(5, 1)}};
  LocalGuidanceConfig lg;
  LocalGuidance guidance(g, 3, lg);
  PibtStep pibt(g, 3, 1);
  MotionForecast f(g, 3, forecast(5), lg);
  WorldView w{g, dist, 0, pos, goals};
  guidance.update(w, {0, 1, 2});
  std::vector<Cell> preferred(3), next(3, kNoCell);
  for (int i = 0; i < 3; ++i) preferred[i] = guidance.next_cell(i, 0, pos[i]);
  pibt.step(w, next, {}, {}, &preferred);
  f.roll(w, next, {0, 1, 2}, pibt, guidance);
  // Step 1: agent 0 is where its forecast says; agent 1 got a new goal; agent 2 rests on its
  // goal, so its forecast never moves.
  std::vector<Cell> pos1 = next;
  std::vector<std::vector<Cell>> goals1 = {{g.cell(9, 0)}, {g.cell(0, 1)}, {g.cell(5, 1)}};
  ASSERT_EQ(f.forecast(2), std::vector<Cell>(5, g.cell(5, 1)));
  const auto own_path = guidance.path_from(2, 1);
  WorldView w1{g, dist, 1, pos1, goals1};
  f.seed(w1, {0, 1, 2}, guidance);
  EXPECT_EQ(guidance.path_from(0, 1), f.forecast(0));
  EXPECT_TRUE(guidance.path_from(1, 1).empty());
  EXPECT_EQ(guidance.path_from(2, 1), own_path);  // kept, not replaced by the parked forecast
}

TEST(MotionForecast, GuidedPibtCorridorHeadOnAllArrive) {
  // A one-lane corridor with a dead-end branch: agents meet head-on and must use the branch.
  Grid g = Grid::from_rows({"..........", "@@@@.@@@@@", "@@@@.@@@@@"});
  LocalGuidanceConfig lg;
  const MotionForecastConfig f = forecast(10);
  PibtPlanner p(g, 2, 3, PibtOptions{}, &lg, &f);
  ListStream tasks({{g.cell(9, 0), g.cell(0, 0)}, {g.cell(0, 0), g.cell(9, 0)}});
  SimResult r = run(g, tasks, p, {g.cell(0, 0), g.cell(9, 0)}, 80);
  EXPECT_GE(r.goals_reached, 4);
  EXPECT_EQ(r.collisions, 0);
}

TEST(MotionForecast, GdRhcrCorridorAndNonBiconnectedMapCollisionFreeWithGoals) {
  const SimResult corridor = test_support::run_corridor_with_pocket(
      [](const Grid& g, int n) { return std::make_unique<GdRhcrPlanner>(g, n, 2, product_with_forecast()); });
  EXPECT_GE(corridor.goals_reached, 5);
  // random-32-32-20 has dead ends and cut cells; 250 agents fill a third of it. Every agent
  // must reach goals (no one starves).
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  GdRhcrPlanner p(g, 250, 6, product_with_forecast());
  RandomNavigationStream tasks(g, 6);
  SimResult r = run(g, tasks, p, random_starts(g, 250, 6), 150);
  EXPECT_GT(r.goals_reached, 500);
  for (size_t i = 0; i < r.paths.size(); ++i) {
    std::vector<Cell> visited(r.paths[i].begin(), r.paths[i].end());
    std::sort(visited.begin(), visited.end());
    EXPECT_GT(std::unique(visited.begin(), visited.end()) - visited.begin(), 1) << "agent " << i << " never moved";
  }
  EXPECT_EQ(p.params()["lg_forecast"].get<int>(), 10);
  EXPECT_EQ(p.params()["lg_forecast_window"].get<int>(), 8);
}

TEST(MotionForecast, DeterministicAndIdenticalAcrossThreadCountsInBudgetMode) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  auto starts = random_starts(g, 300, 7);
  std::vector<std::vector<Cell>> first;
  for (int threads : {1, 1, 2}) {
    GdRhcrConfig cfg = product_with_forecast();
    cfg.threads = threads;
    GdRhcrPlanner p(g, 300, 7, cfg);
    RandomNavigationStream tasks(g, 7);
    SimResult r = run(g, tasks, p, starts, 60);
    EXPECT_GT(r.goals_reached, 0);
    if (first.empty()) first = r.paths;
    else EXPECT_EQ(r.paths, first) << threads << " threads";
  }
}

TEST(MotionForecast, DefaultOnlyOnMapsWithCutCells) {
  auto forecast_of = [](const std::string& map, int agents, const std::string& preset) {
    Grid g = Grid::load(repo("maps/" + map));
    Params p;
    p.set("preset", preset);
    auto planner = make_planner("gd-rhcr", p, g, agents, 1);
    return planner->params()["lg_forecast"].get<int>();
  };
  EXPECT_EQ(forecast_of("random-32-32-20.map", 300, "default"), 8);
  EXPECT_EQ(forecast_of("warehouse-10-20-10-2-1.map", 400, "default"), 0);
  EXPECT_EQ(forecast_of("empty-48-48.map", 400, "default"), 0);
  EXPECT_EQ(forecast_of("random-32-32-20.map", 300, "paper"), 0);
  EXPECT_EQ(forecast_of("random-64-64-20.map", 2500, "default"), 0);  // lazy banded guidance
}
