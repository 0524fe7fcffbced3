// RHCR: hundreds of steps on random-32-32-20 and kiva with zero collisions (the simulator's
// validator throws on any), replanning every alpha steps and at once after a deviation, the
// PIBT fallback, and parameter validation. Node budgets, never wall time, bound PBS here.
#include <gtest/gtest.h>

#include "gdrhcr/rhcr.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

SimResult run_rhcr(const Grid& g, RhcrPlanner& planner, int agents, int steps, uint64_t seed) {
  DistTable dist(g);
  RandomNavigationStream tasks(g, seed);
  SimOptions opt;
  opt.steps = steps;
  return run_simulation(g, dist, tasks, planner, random_starts(g, agents, seed), opt);
}

RhcrConfig budgeted(long nodes) {
  RhcrConfig c;
  c.node_budget = nodes;
  c.timeout_s = 1e6;  // only the node budget may stop PBS
  return c;
}
}  // namespace

TEST(Rhcr, RandomMapHundredsOfStepsNoCollisions) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  for (int agents : {50, 120}) {
    RhcrPlanner planner(g, agents, 1, budgeted(2000));
    SimResult r = run_rhcr(g, planner, agents, 200, 1);
    const auto s = planner.stats();
    EXPECT_EQ(r.collisions, 0);
    EXPECT_GT(r.goals_reached, agents);
    EXPECT_LE(r.throughput, r.free_flow_throughput);
    EXPECT_EQ(s["solver_calls"].get<long>(), r.planned_steps);  // plan time is per PBS call
    EXPECT_GE(s["solver_calls"].get<long>(), 200 / 5);
    EXPECT_EQ(s["deviation_replans"].get<long>(), 0);
  }
}

TEST(Rhcr, KivaHundredsOfStepsNoCollisions) {
  Grid g = Grid::load(repo("maps/kiva.map"));
  RhcrPlanner planner(g, 100, 2, budgeted(3000));
  SimResult r = run_rhcr(g, planner, 100, 300, 2);
  EXPECT_EQ(r.collisions, 0);
  EXPECT_GT(r.throughput, 0.5 * r.free_flow_throughput);
  EXPECT_EQ(planner.stats()["solver_calls"].get<long>(), 300 / 5);
}

TEST(Rhcr, FallsBackToPibtWhenPbsRunsOutOfNodes) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  RhcrPlanner planner(g, 300, 3, budgeted(1));  // the root alone never solves 300 agents
  SimResult r = run_rhcr(g, planner, 300, 100, 3);
  const auto s = planner.stats();
  EXPECT_EQ(r.collisions, 0);
  EXPECT_GT(s["solver_failures"].get<long>(), 0);
  EXPECT_EQ(s["solver_timeouts"].get<long>(), s["solver_failures"].get<long>());
  EXPECT_GE(s["fallback_steps"].get<long>(), 5 * s["solver_failures"].get<long>() - 5);
  EXPECT_GT(r.goals_reached, 0);
}

TEST(Rhcr, ReplansAtOnceWhenARobotLags) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist(g);
  const int n = 40;
  RandomNavigationStream tasks(g, 4);
  std::vector<Cell> pos = random_starts(g, n, 4), next(n);
  std::vector<std::vector<Cell>> goals(n);
  for (int i = 0; i < n; ++i) goals[i] = {tasks.next_goal(i, pos[i])};
  RhcrPlanner planner(g, n, 4, budgeted(2000));
  StepValidator validator(g);
  int planned = 0;
  for (int t = 0; t < 60; ++t) {
    WorldView view{g, dist, t, pos, goals};
    StepReport rep = planner.plan_step(view, next);
    planned += rep.planned;
    validator.require_valid(pos, next, t);
    // At t = 7 and t = 23 every robot lags one step (stays): a valid, unplanned configuration.
    if (t != 7 && t != 23) pos = next;
    for (int i = 0; i < n; ++i)
      if (pos[i] == goals[i][0]) goals[i] = {tasks.next_goal(i, pos[i])};
  }
  const auto s = planner.stats();
  EXPECT_EQ(s["deviation_replans"].get<long>(), 2);
  EXPECT_EQ(planned, s["solver_calls"].get<long>());
  EXPECT_GT(planned, 60 / 5);
}

TEST(Rhcr, RegistryReadsAndValidatesParameters) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  {
    Params p;
    p.set("H", "10");
    p.set("alpha", "3");
    p.set("timeout", "2.5");
    p.set("node-budget", "100");
    auto planner = make_planner("rhcr", p, g, 10, 1);
    EXPECT_TRUE(p.unused().empty());
    const auto j = planner->params();
    EXPECT_EQ(j["H"], 10);
    EXPECT_EQ(j["alpha"], 3);
    EXPECT_EQ(j["timeout"], 2.5);
    EXPECT_EQ(j["node_budget"], 100);
    EXPECT_EQ(planner->name(), "rhcr");
  }
  auto bad = [&](const std::string& k, const std::string& v) {
    Params p;
    p.set(k, v);
    EXPECT_THROW(make_planner("rhcr", p, g, 10, 1), ParamError) << k << "=" << v;
  };
  bad("H", "0");
  bad("alpha", "0");
  bad("alpha", "21");  // > default H
  bad("timeout", "0");
  bad("timeout", "-1");
  bad("node-budget", "-1");
  Params c;
  c.set("c-soft", "1");  // RHCR has no soft constraints: an unknown parameter, named
  try {
    make_planner("rhcr", c, g, 10, 1);
    ADD_FAILURE() << "c-soft accepted by rhcr";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("c-soft"), std::string::npos) << e.what();
  }
}
