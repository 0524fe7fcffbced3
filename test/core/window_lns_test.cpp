// The windowed LNS over the coming steps (window_lns.hpp): every step it executes is valid in the
// model in force (the simulator throws on a conflict), the joint plan it holds is free of
// conflicts and made of the model's actions, the plan's cost is what the file comment says, and
// the search does lower it.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "gdrhcr/planner.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/task_stream.hpp"
#include "gdrhcr/validator.hpp"
#include "gdrhcr/window_lns.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

Params lns_params(int window, int iterations) {
  Params p;
  p.set("lns-window", std::to_string(window));
  p.set("lns-iterations", std::to_string(iterations));
  return p;
}

// Checks the plan the planner holds after a step of `world`: it starts where the agents stand,
// every transition is one action of the model, no two agents share a cell at a time or swap cells,
// and its cost is the sum of each agent's (here, without step costs, every step costs 1: the step it
// first stands on its goal, else the window plus its distance from where the window leaves it).
void check_plan(const WindowLns& lns, const WorldView& world, int window) {
  const auto& plan = lns.plan();
  ASSERT_EQ(static_cast<int>(plan.size()), world.num_agents());
  long cost = 0;
  for (int i = 0; i < world.num_agents(); ++i) {
    ASSERT_EQ(static_cast<int>(plan[i].size()), window + 1);
    EXPECT_EQ(plan[i][0].cell, world.positions[i]);
    const DistRow& row = *world.dist.row(world.goals[i][0]);
    long c = -1;
    for (int t = 0; t <= window && c < 0; ++t)
      if (plan[i][t].cell == row.goal()) c = t;
    if (c < 0) c = window + row.at(plan[i][window].cell, world.rotation() ? plan[i][window].heading : kEast);
    cost += c;
    for (int t = 0; t < window; ++t) {
      if (world.rotation())
        EXPECT_TRUE(action_between(world.grid, plan[i][t], plan[i][t + 1]).has_value()) << "agent " << i << " t " << t;
      else
        EXPECT_TRUE(world.grid.step_allowed(plan[i][t].cell, plan[i][t + 1].cell)) << "agent " << i << " t " << t;
    }
  }
  EXPECT_EQ(cost, lns.plan_cost());
  for (int t = 0; t <= window; ++t) {
    std::map<Cell, int> at;
    for (int i = 0; i < world.num_agents(); ++i) {
      const auto [it, fresh] = at.emplace(plan[i][t].cell, i);
      EXPECT_TRUE(fresh) << "agents " << it->second << " and " << i << " share " << world.grid.describe(plan[i][t].cell)
                         << " at t " << t;
    }
    if (t == 0) continue;
    std::map<std::pair<Cell, Cell>, int> moves;
    for (int i = 0; i < world.num_agents(); ++i)
      if (plan[i][t - 1].cell != plan[i][t].cell) moves[{plan[i][t - 1].cell, plan[i][t].cell}] = i;
    for (auto& [m, i] : moves) EXPECT_EQ(moves.count({m.second, m.first}), 0u) << "agent " << i << " swaps at t " << t;
  }
}

// A fleet on random errands, moved one step at a time by a windowed LNS planner: after each step
// the plan it holds is checked, and its first step must be the one executed.
struct Fleet {
  Fleet(const Grid& g, ActionModel model, int n, uint64_t seed)
      : grid(g), model(model), dist(g, model), tasks(g, seed), pos(random_starts(g, n, seed)), heads(n, kEast),
        next_heads(n, kEast), goals(n) {
    for (int i = 0; i < n; ++i) goals[i] = {tasks.next_goal(i, pos[i])};
  }
  void step(Planner& planner, const WindowLns& lns, int t, int window) {
    const int n = static_cast<int>(pos.size());
    WorldView world{grid, dist, t, pos, goals};
    world.action_model = model;
    if (model == ActionModel::kRotation) world.headings = &heads, world.next_headings = &next_heads;
    std::vector<Cell> next(n);
    planner.plan_step(world, next);
    check_plan(lns, world, window);
    for (int i = 0; i < n; ++i) {
      EXPECT_EQ(next[i], lns.plan()[i][1].cell);  // the plan's first step is what is executed
      pos[i] = next[i];
      heads[i] = next_heads[i];
      if (pos[i] == goals[i][0]) goals[i] = {tasks.next_goal(i, pos[i])};
    }
  }
  const Grid& grid;
  ActionModel model;
  DistTable dist;
  RandomNavigationStream tasks;
  std::vector<Cell> pos;
  std::vector<Heading> heads, next_heads;
  std::vector<std::vector<Cell>> goals;
};
}  // namespace

TEST(WindowLns, HoldsAConflictFreePlanOfTheModelsActionsAndLowersItsCost) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  for (ActionModel model : {ActionModel::kRotation, ActionModel::kMapf}) {
    SCOPED_TRACE(action_model_name(model));
    const int n = 200, window = 8;
    Fleet fleet(g, model, n, 3);
    Params params = lns_params(window, 200);
    auto planner = make_planner("gd-rhcr", params, g, n, 3, model);
    auto* lns = dynamic_cast<WindowLns*>(planner.get());
    ASSERT_NE(lns, nullptr) << "lns-window > 0 wraps GD-RHCR in the windowed LNS";
    long gained = 0;
    for (int step = 0; step < 20; ++step) {
      fleet.step(*planner, *lns, step, window);
      gained = planner->stats()["lns_cost_gained"].get<long>();
    }
    EXPECT_GT(gained, 0) << "200 neighbourhoods a step never lowered the plan's cost";
    EXPECT_GT(planner->stats()["lns_kept"].get<long>(), 0);
  }
}

// An agent's errand is done the first time it stands on its goal, and it may leave the goal after
// that (it gets its next errand there): here agent 0 reaches its goal, at the mouth of a pocket, at
// once and steps into the pocket so that agent 1 can pass. Holding the goal to the window's end
// would leave agent 1 no way through.
TEST(WindowLns, AnAgentOnItsGoalMakesWay) {
  const Grid g = Grid::from_rows({".....", "@@.@@"});
  DistTable dist(g, ActionModel::kMapf);
  const int window = 8;
  std::vector<Cell> pos{g.cell(1, 0), g.cell(4, 0)};
  std::vector<std::vector<Cell>> goals{{g.cell(2, 0)}, {g.cell(0, 0)}};
  Params params = lns_params(window, 200);
  auto planner = make_planner("gd-rhcr", params, g, 2, 1, ActionModel::kMapf);
  auto& lns = dynamic_cast<WindowLns&>(*planner);
  WorldView world{g, dist, 0, pos, goals};
  std::vector<Cell> next(2);
  planner->plan_step(world, next);
  check_plan(lns, world, window);
  EXPECT_EQ(lns.plan_cost(), 1 + 4) << "agent 0 arrives at step 1, agent 1 at step 4";
  EXPECT_EQ(lns.plan()[0][1].cell, g.cell(2, 0));
  EXPECT_EQ(lns.plan()[0][2].cell, g.cell(2, 1)) << "agent 0 steps into the pocket";
  EXPECT_EQ(lns.plan()[1][4].cell, g.cell(0, 0));
}

// With threads, stripes of the map far enough apart are searched at once (one thread each), then
// everyone together: the plan stays conflict-free, the search still lowers its cost, and with a
// fixed number of neighbourhoods two runs make the same plan.
TEST(WindowLns, ZonesSearchedAtOnceKeepThePlanConflictFreeAndRunsReproducible) {
  const Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  const ActionModel model = ActionModel::kRotation;
  const int n = 400, window = 5;
  std::vector<std::vector<std::vector<Pose>>> plans(2);
  for (int run = 0; run < 2; ++run) {
    Fleet fleet(g, model, n, 7);
    Params params = lns_params(window, 300);
    params.set("threads", "2");
    auto planner = make_planner("gd-rhcr", params, g, n, 7, model);
    auto& lns = dynamic_cast<WindowLns&>(*planner);
    for (int step = 0; step < 10; ++step) fleet.step(*planner, lns, step, window);
    const auto stats = planner->stats();
    EXPECT_EQ(stats["lns_steps_zoned"].get<long>(), 10) << "161 columns hold two zones every step";
    EXPECT_GT(stats["lns_cost_gained"].get<long>(), 0);
    plans[run] = lns.plan();
  }
  EXPECT_TRUE(plans[0] == plans[1]) << "a fixed number of neighbourhoods makes the same plan with threads";
}

// A neighbourhood in which some agent finds no path (an agent planned before it took the cells it
// needed) is planned again with that agent first, up to four tries. On a crowded map most
// neighbourhoods then succeed: with one retry only, a sixth of them failed here (Paris jammed when
// nearly half failed: docs/results.md, session 29).
TEST(WindowLns, NeighbourhoodsWhereAnAgentFindsNoPathAreTriedAgainWithItFirst) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  const int n = 200, window = 8;
  Fleet fleet(g, ActionModel::kRotation, n, 3);
  Params params = lns_params(window, 200);
  auto planner = make_planner("gd-rhcr", params, g, n, 3, ActionModel::kRotation);
  auto& lns = dynamic_cast<WindowLns&>(*planner);
  for (int step = 0; step < 20; ++step) fleet.step(*planner, lns, step, window);
  const auto stats = planner->stats();
  const double tried = stats["lns_neighbourhoods"].get<double>(), failed = stats["lns_failed_searches"].get<double>();
  ASSERT_GT(tried, 1000);
  EXPECT_LT(failed / tried, 0.07) << failed << " of " << tried << " neighbourhoods failed";
  EXPECT_GT(failed, 0) << "no neighbourhood failed: this fleet no longer tests the retries";
}

TEST(WindowLns, RunsAreValidAndReachGoalsInBothModels) {
  for (ActionModel model : {ActionModel::kRotation, ActionModel::kMapf}) {
    for (const char* map : {"random-32-32-20.map", "warehouse-10-20-10-2-1.map", "room-32-32-4.map"}) {
      SCOPED_TRACE(std::string(map) + " in " + action_model_name(model));
      const Grid g = Grid::load(repo(std::string("maps/") + map));
      DistTable dist(g, model);
      RandomNavigationStream tasks(g, 5);
      const int n = 120;
      const auto starts = random_starts(g, n, 5);
      Params params = lns_params(10, 30);
      auto planner = make_planner("gd-rhcr", params, g, n, 5, model);
      SimOptions opt;
      opt.steps = 60;
      opt.action_model = model;
      const SimResult r = run_simulation(g, dist, tasks, *planner, starts, opt);
      EXPECT_EQ(r.collisions, 0);
      EXPECT_GT(r.goals_reached, n / 4);
      EXPECT_GT(planner->stats()["lns_kept"].get<long>(), 0);
    }
  }
}

TEST(WindowLns, StepsOfThePlannerBeneathAreKeptWhenRobotsCannotMove) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  const int n = 60;
  DistTable dist(g, ActionModel::kMapf);
  RandomNavigationStream tasks(g, 9);
  std::vector<Cell> pos = random_starts(g, n, 9);
  std::vector<std::vector<Cell>> goals(n);
  for (int i = 0; i < n; ++i) goals[i] = {tasks.next_goal(i, pos[i])};
  std::vector<uint8_t> immovable(n, 0);
  immovable[0] = 1;
  Params params = lns_params(6, 50);
  auto planner = make_planner("gd-rhcr", params, g, n, 9, ActionModel::kMapf);
  WorldView world{g, dist, 0, pos, goals, &immovable};
  std::vector<Cell> next(n);
  planner->plan_step(world, next);
  EXPECT_EQ(next[0], pos[0]);
  EXPECT_TRUE(dynamic_cast<WindowLns&>(*planner).plan().empty()) << "no search beside a robot that cannot move";
  EXPECT_EQ(planner->stats()["lns_steps"].get<long>(), 0);
}

// Without a budget the search does not run, and the wrapper answers for the planner beneath
// exactly: its step, its planned paths and the cell it means each agent to enter next (GD-RHCR's
// from its guidance; the ROS executor's catch-up reads it).
TEST(WindowLns, WithoutABudgetItIsThePlannerBeneath) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  const int n = 100;
  for (ActionModel model : {ActionModel::kRotation, ActionModel::kMapf}) {
    SCOPED_TRACE(action_model_name(model));
    DistTable dist(g, model);
    RandomNavigationStream tasks(g, 4);
    std::vector<Cell> pos = random_starts(g, n, 4);
    std::vector<Heading> heads(n, kEast), next_heads(n, kEast), plain_heads(n, kEast);
    std::vector<std::vector<Cell>> goals(n);
    for (int i = 0; i < n; ++i) goals[i] = {tasks.next_goal(i, pos[i])};
    Params with, without;
    with.set("lns-window", "10");
    without.set("lns-window", "0");
    auto wrapped = make_planner("gd-rhcr", with, g, n, 4, model);
    auto plain = make_planner("gd-rhcr", without, g, n, 4, model);
    ASSERT_NE(dynamic_cast<WindowLns*>(wrapped.get()), nullptr);
    int compared = 0;
    for (int step = 0; step < 15; ++step) {
      WorldView a{g, dist, step, pos, goals}, b{g, dist, step, pos, goals};
      a.action_model = b.action_model = model;
      if (model == ActionModel::kRotation) {
        a.headings = b.headings = &heads;
        a.next_headings = &next_heads, b.next_headings = &plain_heads;
      }
      std::vector<Cell> na(n), nb(n);
      wrapped->plan_step(a, na);
      plain->plan_step(b, nb);
      ASSERT_EQ(na, nb);
      for (int i = 0; i < n; ++i) {
        ASSERT_EQ(wrapped->planned_path(i), plain->planned_path(i));
        ASSERT_EQ(wrapped->intended_next(i, na[i]), plain->intended_next(i, na[i]));
        compared += plain->intended_next(i, na[i]) != kNoCell;
      }
      pos = na;
      if (model == ActionModel::kRotation) {
        ASSERT_EQ(next_heads, plain_heads);
        heads = next_heads;
      }
      for (int i = 0; i < n; ++i)
        if (pos[i] == goals[i][0]) goals[i] = {tasks.next_goal(i, pos[i])};
    }
    EXPECT_GT(compared, 0) << "GD-RHCR named no next cell at all";
  }
}

// A budget too short for the planner beneath and two rollout steps: the first step (nothing measured
// yet) begins a rollout, which is cut at the stop; from then on no rollout is begun, the planner
// beneath gets the whole budget, and every step is valid.
TEST(WindowLns, NoRolloutIsBegunThatCouldNotEndBeforeTheStop) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  const int n = 150, steps = 20;
  DistTable dist(g, ActionModel::kRotation);
  RandomNavigationStream tasks(g, 6);
  Params params;
  params.set("lns-window", "8");
  params.set("step-budget", "1e-9");
  auto planner = make_planner("gd-rhcr", params, g, n, 6, ActionModel::kRotation);
  ASSERT_NE(dynamic_cast<WindowLns*>(planner.get()), nullptr);
  SimOptions opt;
  opt.steps = steps;
  opt.action_model = ActionModel::kRotation;
  const SimResult r = run_simulation(g, dist, tasks, *planner, random_starts(g, n, 6), opt);
  EXPECT_EQ(r.collisions, 0);
  const auto stats = planner->stats();
  EXPECT_EQ(stats["lns_steps"].get<long>(), 0);
  EXPECT_EQ(stats["lns_steps_cut"].get<long>(), 1);
  EXPECT_EQ(stats["lns_steps_skipped"].get<long>(), steps - 1);
  EXPECT_GT(stats["lns_rollout_step_ms"].get<double>(), 0);
}

// With a budget, a step searches only when its whole rollout fits: every plan it holds spans the
// window, is conflict-free, made of the model's actions, and executed.
TEST(WindowLns, UnderABudgetEachHeldPlanSpansTheWindowAndIsValid) {
  const Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  const int n = 400, window = 10;
  Fleet fleet(g, ActionModel::kRotation, n, 2);
  Params params;
  params.set("lns-window", std::to_string(window));
  params.set("step-budget", "1");  // ample even under the sanitizers
  auto planner = make_planner("gd-rhcr", params, g, n, 2, ActionModel::kRotation);
  auto& lns = dynamic_cast<WindowLns&>(*planner);
  int held = 0;
  for (int t = 0; t < 12; ++t) {
    WorldView world{g, fleet.dist, t, fleet.pos, fleet.goals};
    world.action_model = ActionModel::kRotation;
    world.headings = &fleet.heads, world.next_headings = &fleet.next_heads;
    std::vector<Cell> next(n);
    planner->plan_step(world, next);
    const auto& plan = lns.plan();
    if (!plan.empty()) {
      ++held;
      check_plan(lns, world, window);
      for (int i = 0; i < n; ++i) EXPECT_EQ(next[i], plan[i][1].cell);
    }
    StepValidator v(g, ActionModel::kRotation);
    const auto bad = v.check(fleet.pos, next, &fleet.heads, &fleet.next_heads);
    ASSERT_FALSE(bad) << bad->describe(g, t);
    for (int i = 0; i < n; ++i) {
      fleet.pos[i] = next[i], fleet.heads[i] = fleet.next_heads[i];
      if (fleet.pos[i] == fleet.goals[i][0]) fleet.goals[i] = {fleet.tasks.next_goal(i, fleet.pos[i])};
    }
  }
  EXPECT_GT(held, 0) << "a second for 400 agents left no step a search: " << planner->stats().dump();
}

TEST(WindowLns, OnByTheRuleOnlyInTheRotationModelWithRoomToGoRound) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));  // 819 free cells
  Params none;
  auto sparse = make_planner("gd-rhcr", none, g, 200, 1, ActionModel::kRotation);
  EXPECT_NE(dynamic_cast<WindowLns*>(sparse.get()), nullptr) << "200 agents hold a quarter of the free cells";
  Params none2;
  auto dense = make_planner("gd-rhcr", none2, g, 250, 1, ActionModel::kRotation);
  EXPECT_EQ(dynamic_cast<WindowLns*>(dense.get()), nullptr) << "250 agents hold 30.5% of them";
  Params none3;
  auto mapf = make_planner("gd-rhcr", none3, g, 200, 1, ActionModel::kMapf);
  EXPECT_EQ(dynamic_cast<WindowLns*>(mapf.get()), nullptr);
  Params paper;
  paper.set("preset", "paper");
  auto preset = make_planner("gd-rhcr", paper, g, 200, 1, ActionModel::kRotation);
  EXPECT_EQ(dynamic_cast<WindowLns*>(preset.get()), nullptr) << "the paper's configuration has no LNS";
}

TEST(WindowLns, BadValuesAreRefused) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  Params bad;
  bad.set("lns-window", "-3");
  EXPECT_THROW(make_planner("gd-rhcr", bad, g, 10, 1, ActionModel::kRotation), ParamError);
  Params bad_n;
  bad_n.set("lns-neighbours", "0");
  EXPECT_THROW(make_planner("gd-rhcr", bad_n, g, 10, 1, ActionModel::kRotation), ParamError);
}
