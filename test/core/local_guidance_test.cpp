// Local guidance (local_guidance.hpp) and the solvers that follow it: guided PIBT and GD-RHCR's
// product configuration. Every simulation validates every executed step (a collision throws).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>

#include "solver_scenarios.hpp"

#include "gdrhcr/gd_rhcr.hpp"
#include "preset_config.hpp"
#include "gdrhcr/local_guidance.hpp"
#include "gdrhcr/guided_pibt.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/task_stream.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

using gdrhcr::test_support::ListStream;
using gdrhcr::test_support::run;

bool is_walk(const Grid& g, const std::vector<Cell>& path) {
  for (size_t k = 0; k + 1 < path.size(); ++k)
    if (path[k] != path[k + 1] && !g.step_allowed(path[k], path[k + 1])) return false;
  return true;
}

GdRhcrConfig product_budget_config() {
  GdRhcrConfig c = preset_config("default");
  c.node_budget = 200;
  c.timeout_s = 1e6;
  return c;
}
}  // namespace

TEST(LocalGuidance, PathIsAWalkFromTheAgentToItsGoal) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist(g);
  LocalGuidance lg(g, 1, {});
  auto starts = random_starts(g, 2, 5);
  std::vector<Cell> pos = {starts[0]};
  std::vector<std::vector<Cell>> goals = {{starts[1]}};
  WorldView w{g, dist, 0, pos, goals};
  lg.update(w, {0});
  const auto path = lg.path_from(0, 0);
  ASSERT_FALSE(path.empty());
  EXPECT_EQ(path.front(), pos[0]);
  EXPECT_TRUE(is_walk(g, path));
  EXPECT_LE(static_cast<int>(path.size()), lg.config().window + 1);
  const int d = dist.get(starts[1], starts[0]);
  if (d <= lg.config().window) {  // alone: a shortest path that ends on the goal
    EXPECT_EQ(path.back(), starts[1]);
    EXPECT_EQ(static_cast<int>(path.size()) - 1, d);
  } else {  // it gets as near as the window allows
    EXPECT_EQ(dist.get(starts[1], path.back()), d - lg.config().window);
  }
  EXPECT_EQ(lg.next_cell(0, 0, pos[0]), path[1]);
  EXPECT_EQ(lg.next_cell(0, 0, path[1] == pos[0] ? kNoCell : path[1]), kNoCell);  // not where it stands
}

TEST(LocalGuidance, SecondPathAvoidsTheFirstWhenALaneIsFree) {
  // Two lanes; agent 0 is guided first along the top lane eastwards. Agent 1 heads west from
  // the top lane's east end: the cheapest plan that meets no one drops to the bottom lane.
  Grid g = Grid::from_rows({"........", "........"});
  DistTable dist(g);
  LocalGuidanceConfig cfg;
  cfg.window = 10;
  LocalGuidance lg(g, 2, cfg);
  std::vector<Cell> pos = {g.cell(0, 0), g.cell(7, 0)};
  std::vector<std::vector<Cell>> goals = {{g.cell(7, 0)}, {g.cell(0, 0)}};
  WorldView w{g, dist, 0, pos, goals};
  lg.update(w, {0, 1});
  const auto a = lg.path_from(0, 0), b = lg.path_from(1, 0);
  ASSERT_EQ(a.size(), 8u);
  for (Cell c : a) EXPECT_EQ(g.y_of(c), 0);  // the first keeps its straight path
  for (size_t t = 0; t < b.size(); ++t) {
    if (t < a.size()) EXPECT_NE(b[t], a[t]) << "vertex conflict at " << t;
    if (t + 1 < a.size() && t + 1 < b.size()) EXPECT_FALSE(b[t] == a[t + 1] && b[t + 1] == a[t]) << "swap at " << t;
  }
  EXPECT_EQ(b.back(), g.cell(0, 0));
  EXPECT_LE(b.size(), 11u);  // a detour of two steps at most
}

TEST(LocalGuidance, AStepMeetingAParkedAndAnOncomingPathPaysPerKindOfConflict) {
  // Agent 0 at (0,0) heads for (2,0). The direct step into (1,0) meets agent 1, which parks
  // there, and swaps with agent 2, which comes the other way and parks on (0,0) (so waiting
  // there conflicts too). Per kind of conflict that step costs 2 x 3 on top of the two moves (8),
  // more than the free six-step detour round the wall; counted once (3, total 5) it is cheaper.
  Grid g = Grid::from_rows({"...", ".@.", "..."});
  DistTable dist(g);
  const Cell a0 = g.cell(0, 0), mid = g.cell(1, 0), goal = g.cell(2, 0);
  std::vector<Cell> pos = {a0, goal, mid};
  std::vector<std::vector<Cell>> goals = {{goal}, {mid}, {a0}};
  for (bool per_kind : {true, false}) {
    LocalGuidanceConfig cfg;
    cfg.window = 10;
    cfg.cost_per_kind = per_kind;
    LocalGuidance lg(g, 3, cfg);
    std::vector<Cell> parks_in_mid(11, mid), parks_in_a0(11, a0);
    parks_in_mid[0] = goal;  // agent 1: (2,0) -> (1,0), then stays
    parks_in_a0[0] = mid;    // agent 2: (1,0) -> (0,0), then stays
    lg.set_path(1, 0, parks_in_mid, mid);
    lg.set_path(2, 0, parks_in_a0, a0);
    WorldView w{g, dist, 0, pos, goals};
    lg.update(w, {0});
    const auto path = lg.path_from(0, 0);
    ASSERT_FALSE(path.empty());
    EXPECT_TRUE(is_walk(g, path));
    EXPECT_EQ(path.back(), goal);
    if (per_kind) {
      EXPECT_EQ(path.size(), 7u) << "the detour round the wall";
      EXPECT_EQ(path[1], g.cell(0, 1));
    } else {
      EXPECT_EQ(path.size(), 3u) << "straight through";
      EXPECT_EQ(path[1], mid);
    }
  }
}

TEST(LocalGuidance, ConflictsFarAheadCostTheFarCost) {
  // Two lanes; agent 0 runs east along the top one, agent 1 parks on it. Passing through the
  // parked agent costs a collision, going round it two steps. With a far cost of 1 from 3 steps
  // ahead, a conflict 4 steps ahead is passed through; one 1 step ahead is still gone round.
  Grid g = Grid::from_rows({"........", "........"});
  DistTable dist(g);
  auto path_past = [&](int parked_x, double far_cost) {
    LocalGuidanceConfig cfg;
    cfg.window = 12;
    cfg.far_collision_cost = far_cost;
    cfg.near_steps = 3;
    LocalGuidance lg(g, 2, cfg);
    const Cell parked = g.cell(parked_x, 0);
    lg.set_path(1, 0, std::vector<Cell>(13, parked), parked);
    std::vector<Cell> pos = {g.cell(0, 0), parked};
    std::vector<std::vector<Cell>> goals = {{g.cell(7, 0)}, {parked}};
    WorldView w{g, dist, 0, pos, goals};
    lg.update(w, {0});
    const auto path = lg.path_from(0, 0);
    EXPECT_TRUE(is_walk(g, path));
    EXPECT_EQ(path.back(), g.cell(7, 0));
    return path;
  };
  const Cell far_parked = g.cell(5, 0), near_parked = g.cell(2, 0);
  auto through = [](const std::vector<Cell>& p, Cell c) { return std::find(p.begin(), p.end(), c) != p.end(); };
  EXPECT_FALSE(through(path_past(5, -1), far_parked)) << "without a far cost: round";
  EXPECT_TRUE(through(path_past(5, 1.0), far_parked)) << "4 steps ahead: through";
  EXPECT_EQ(path_past(5, 1.0).size(), 8u);
  EXPECT_FALSE(through(path_past(2, 1.0), near_parked)) << "1 step ahead: round";
}

TEST(LocalGuidance, RejectsNonsenseConfig) {
  Grid g = Grid::from_rows({"...."});
  LocalGuidanceConfig c;
  c.window = 0;
  EXPECT_THROW(LocalGuidance(g, 1, c), ParamError);
  c.window = 5;
  c.collision_cost = -1;
  EXPECT_THROW(LocalGuidance(g, 1, c), ParamError);
  c.collision_cost = 3;
  c.near_steps = -1;
  EXPECT_THROW(LocalGuidance(g, 1, c), ParamError);
  c.near_steps = 3;
  c.contraflow_cost = -0.1;
  EXPECT_THROW(LocalGuidance(g, 1, c), ParamError);
}

TEST(LocalGuidance, ContraflowSendsAnAgentRoundTheRouteNobodyTakesTheOtherWay) {
  // Two routes of ten steps from (0,2) to (6,2): over the top row or along the bottom one.
  // Agent 0 waits in a pocket at (7,0) and, once agent 1 would be through, walks the top row
  // westwards: no conflict in space and time with either route, but it goes against the top
  // route's direction. Without a contraflow cost the routes tie (random neighbour order picks
  // one); with it agent 1 always takes the bottom route.
  Grid g = Grid::from_rows({"........", ".@@@@@.@", ".@@@@@.@", ".@@@@@.@", ".......@"});
  DistTable dist(g);
  const Cell start = g.cell(0, 2), goal = g.cell(6, 2);
  std::vector<Cell> west(12, g.cell(7, 0));
  for (int x = 6; x >= 0; --x) west.push_back(g.cell(x, 0));
  std::vector<Cell> pos = {g.cell(7, 0), start};
  std::vector<std::vector<Cell>> goals = {{g.cell(0, 0)}, {goal}};
  WorldView w{g, dist, 0, pos, goals};
  for (double contraflow : {0.0, 0.1}) {
    int top = 0;
    for (uint64_t seed = 1; seed <= 12; ++seed) {
      LocalGuidanceConfig cfg;
      cfg.window = 20;
      cfg.seed = seed;
      cfg.contraflow_cost = contraflow;
      LocalGuidance lg(g, 2, cfg);
      lg.set_path(0, 0, west, goals[0][0]);
      lg.update(w, {1});
      const auto p = lg.path_from(1, 0);
      ASSERT_EQ(p.size(), 11u) << "a shortest path either way";
      ASSERT_EQ(p.back(), goal);
      ASSERT_TRUE(is_walk(g, p));
      top += g.y_of(p[5]) == 0;
    }
    if (contraflow > 0) EXPECT_EQ(top, 0) << "against the other agent's direction";
    else EXPECT_GT(top, 0) << "the routes tie without a contraflow cost";
  }
}

// lg-straight: on an open 8 x 8 grid, from corner to corner every monotone path is shortest.
// With the random neighbour order the paths zigzag; with lg-straight every path found turns
// once, as few times as a shortest path can, and is still shortest.
TEST(LocalGuidance, StraightPathsTurnAsFewTimesAsAShortestPathCan) {
  const Grid g = Grid::from_rows(std::vector<std::string>(8, "........"));
  DistTable dist(g);
  std::vector<Cell> pos = {g.cell(0, 0)};
  std::vector<std::vector<Cell>> goals = {{g.cell(7, 7)}};
  WorldView w{g, dist, 0, pos, goals};
  for (bool straight : {false, true}) {
    int most_turns = 0;
    for (uint64_t seed = 1; seed <= 12; ++seed) {
      LocalGuidanceConfig cfg;
      cfg.window = 20;
      cfg.seed = seed;
      cfg.straight = straight;
      LocalGuidance lg(g, 1, cfg);
      lg.update(w, {0});
      const auto p = lg.path_from(0, 0);
      ASSERT_EQ(p.size(), 15u) << "a shortest path";
      ASSERT_TRUE(is_walk(g, p));
      int turns = 0;
      for (size_t k = 2; k < p.size(); ++k) turns += p[k] - p[k - 1] != p[k - 1] - p[k - 2];
      most_turns = std::max(most_turns, turns);
    }
    if (straight) EXPECT_EQ(most_turns, 1);
    else EXPECT_GT(most_turns, 1) << "random neighbour order zigzags";
  }
}

TEST(LocalGuidance, PathEndsOnAGoalAnotherAgentRestsOn) {
  // Agent 1 rests on agent 0's goal, next to agent 0. Every step onto the goal costs a
  // collision, so waiting beside it is as cheap for a few steps; the guidance must still lead
  // onto the goal (PIBT then pushes the resting agent away), not wait there for ever.
  Grid g = Grid::from_rows({"......", "......"});
  DistTable dist(g);
  LocalGuidance lg(g, 2, {});
  std::vector<Cell> pos = {g.cell(2, 0), g.cell(1, 0)};
  std::vector<std::vector<Cell>> goals = {{g.cell(1, 0)}, {g.cell(1, 0)}};
  WorldView w{g, dist, 0, pos, goals};
  lg.update(w, {1, 0});
  const auto path = lg.path_from(0, 0);
  ASSERT_FALSE(path.empty());
  EXPECT_EQ(path.back(), g.cell(1, 0));
  EXPECT_EQ(lg.next_cell(0, 0, pos[0]), g.cell(1, 0));
}

// Refinement (the anytime part): agent 0 is guided first, through the cell where agent 1 rests
// (agent 1 is searched later, so agent 0 did not see it). A refinement pass searches agent 0's
// path again with agent 1's in the table: the detour round the top row (4 steps) is cheaper than
// the collision (cost 10). Without refinement the paths meet; by default (-1) the passes run only
// when the update has a deadline (a step budget).
TEST(LocalGuidance, RefinementSearchesAgainAPathThatMeetsALaterOne) {
  Grid g = Grid::from_rows({".....", ".@@@.", "....."});
  DistTable dist(g);
  std::vector<Cell> pos = {g.cell(0, 2), g.cell(2, 2)};
  std::vector<std::vector<Cell>> goals = {{g.cell(4, 2)}, {g.cell(2, 2)}};
  WorldView w{g, dist, 0, pos, goals};
  auto through_rester = [&](int refine, std::chrono::steady_clock::time_point deadline) {
    LocalGuidanceConfig cfg;
    cfg.window = 12;
    cfg.collision_cost = 10;
    cfg.refine = refine;
    LocalGuidance lg(g, 2, cfg);
    lg.update(w, {0, 1}, deadline);
    const auto a = lg.path_from(0, 0);
    EXPECT_TRUE(is_walk(g, a));
    EXPECT_EQ(a.back(), g.cell(4, 2));
    return std::make_pair(std::count(a.begin(), a.end(), g.cell(2, 2)) > 0, lg.refined());
  };
  const auto never = std::chrono::steady_clock::time_point::max();
  const auto later = std::chrono::steady_clock::now() + std::chrono::hours(1);
  EXPECT_EQ(through_rester(0, never), std::make_pair(true, 0L));
  EXPECT_EQ(through_rester(1, never).first, false);
  EXPECT_GE(through_rester(1, never).second, 1L);
  EXPECT_EQ(through_rester(-1, never), std::make_pair(true, 0L));
  EXPECT_EQ(through_rester(-1, later).first, false);
}

// The planner-restart rostest's deadlock, in the core: a robot delivering to a cell where an
// idle robot is parked (its goal is its own cell) must get there; guided PIBT and GD-RHCR's
// product configuration used to leave it waiting beside the cell for ever.
TEST(GuidedPibt, ReachesAGoalAnIdleAgentIsParkedOn) {
  Grid g = Grid::from_rows({"..........", "..........", ".........."});
  DistTable dist(g);
  const Cell goal = g.cell(1, 1);
  LocalGuidanceConfig lg;
  PibtPlanner pibt(g, 2, 1, PibtOptions{}, &lg);
  GdRhcrPlanner gd(g, 2, 1, preset_config("default"));
  StepValidator check(g);
  for (Planner* p : std::vector<Planner*>{&pibt, &gd}) {
    std::vector<Cell> pos = {g.cell(9, 1), goal};
    std::vector<std::vector<Cell>> goals = {{goal}, {goal}};
    int t = 0;
    for (; t < 40 && pos[0] != goal; ++t) {
      goals[1] = {pos[1]};  // idle: stays where it is unless pushed
      WorldView w{g, dist, t, pos, goals};
      std::vector<Cell> next(pos.size(), kNoCell);
      p->plan_step(w, next);
      ASSERT_FALSE(check.check(pos, next).has_value()) << p->name();
      pos = next;
    }
    EXPECT_EQ(pos[0], goal) << p->name() << " did not reach the goal in " << t << " steps";
  }
}

TEST(GuidedPibt, CorridorHeadOnAllArrive) {
  // A one-lane corridor with a dead-end branch: agents meet head-on and must use the branch.
  Grid g = Grid::from_rows({"..........", "@@@@.@@@@@", "@@@@.@@@@@"});
  LocalGuidanceConfig lg;
  PibtPlanner p(g, 2, 3, PibtOptions{}, &lg);
  ListStream tasks({{g.cell(9, 0), g.cell(0, 0)}, {g.cell(0, 0), g.cell(9, 0)}});
  SimResult r = run(g, tasks, p, {g.cell(0, 0), g.cell(9, 0)}, 80);
  EXPECT_GE(r.goals_reached, 4);
  EXPECT_EQ(r.collisions, 0);
}

TEST(GuidedPibt, DenseNonBiconnectedMapBeatsPlainPibt) {
  // random-32-32-20 has dead ends and cut cells; 300 agents fill 37% of it.
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  auto starts = random_starts(g, 300, 4);
  LocalGuidanceConfig lg;
  PibtPlanner guided(g, 300, 4, PibtOptions{}, &lg), plain(g, 300, 4);
  RandomNavigationStream t1(g, 4), t2(g, 4);
  SimResult a = run(g, t1, guided, starts, 150);
  SimResult b = run(g, t2, plain, starts, 150);
  EXPECT_GT(a.goals_reached, b.goals_reached);
  EXPECT_LE(a.throughput, a.free_flow_throughput);
  EXPECT_GT(guided.stats()["guidance_searches"].get<long>(), 0);
}

TEST(GdRhcrProduct, CorridorAndNonBiconnectedMapsCollisionFreeWithGoals) {
  const SimResult corridor = test_support::run_corridor_with_pocket(
      [](const Grid& g, int n) { return std::make_unique<GdRhcrPlanner>(g, n, 2, product_budget_config()); });
  EXPECT_GE(corridor.goals_reached, 5);
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  GdRhcrPlanner p(g, 250, 6, product_budget_config());
  RandomNavigationStream tasks(g, 6);
  SimResult r = run(g, tasks, p, random_starts(g, 250, 6), 100);
  EXPECT_GT(r.goals_reached, 300);
  EXPECT_GT(p.stats()["density_fallbacks"].get<long>() + p.stats()["threshold_fallbacks"].get<long>(), 0);
}

TEST(GdRhcrProduct, SparseGroupsStillUseThePrimarySolver) {
  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  GdRhcrPlanner p(g, 60, 3, product_budget_config());
  RandomNavigationStream tasks(g, 3);
  SimResult r = run(g, tasks, p, random_starts(g, 60, 3), 60);
  EXPECT_GT(r.goals_reached, 0);
  EXPECT_GT(p.stats()["primary_calls"].get<long>(), 0);
}

TEST(GdRhcrProduct, IdenticalResultsAcrossThreadCountsInBudgetMode) {
  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  auto starts = random_starts(g, 400, 9);
  std::vector<std::vector<Cell>> first;
  for (int threads : {1, 2, 4}) {
    GdRhcrConfig cfg = product_budget_config();
    cfg.threads = threads;
    GdRhcrPlanner p(g, 400, 9, cfg);
    RandomNavigationStream tasks(g, 9);
    SimResult r = run(g, tasks, p, starts, 60);
    if (first.empty()) first = r.paths;
    else EXPECT_EQ(r.paths, first) << threads << " threads";
  }
}

TEST(GdRhcrProduct, BandedGuidanceIdenticalAcrossThreadCounts) {
  // The parallel guidance update (bands of the map in two phases, lazy as past 2,000 agents)
  // draws its random numbers per band and step, so the run does not depend on the threads.
  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  auto starts = random_starts(g, 500, 5);
  std::vector<std::vector<Cell>> first;
  long first_searches = 0;
  for (int threads : {1, 2, 3}) {
    GdRhcrConfig cfg = product_budget_config();
    cfg.threads = threads;
    cfg.lg.phases = 2;
    cfg.lg.lazy = true;
    GdRhcrPlanner p(g, 500, 5, cfg);
    RandomNavigationStream tasks(g, 5);
    SimResult r = run(g, tasks, p, starts, 60);
    EXPECT_GT(r.goals_reached, 0);
    const long searches = p.stats()["guidance_searches"].get<long>();
    EXPECT_GT(searches, 0);
    if (first.empty()) {
      first = r.paths, first_searches = searches;
    } else {
      EXPECT_EQ(r.paths, first) << threads << " threads";
      EXPECT_EQ(searches, first_searches) << threads << " threads";
    }
  }
}

TEST(LocalGuidance, BandedUpdateKeepsApartAgentsApartAndRejectsOnePhase) {
  // Bands of one phase are 2W cells apart or more: a search there cannot reach another's cells.
  Grid g = Grid::load(repo("maps/empty-48-48.map"));
  LocalGuidanceConfig cfg;
  cfg.window = 6;
  for (int phases : {2, 3, 5}) {
    cfg.phases = phases;
    LocalGuidance lg(g, 1, cfg);
    EXPECT_GE(lg.band_width() * (phases - 1), 2 * cfg.window) << phases;
  }
  cfg.phases = 1;
  EXPECT_THROW(LocalGuidance(g, 1, cfg), ParamError);
  // Two agents at both ends of a row, each heading past the other's start (bands 0 and 3 of
  // width 12): their banded paths are shortest walks from their own cells.
  cfg.phases = 2;
  LocalGuidance banded(g, 2, cfg);
  DistTable dist(g);
  std::vector<Cell> pos = {g.cell(1, 10), g.cell(46, 10)};
  std::vector<std::vector<Cell>> goals = {{g.cell(40, 10)}, {g.cell(7, 10)}};
  WorldView w{g, dist, 0, pos, goals};
  banded.update(w, {0, 1});
  for (int i : {0, 1}) {
    const auto path = banded.path_from(i, 0);
    ASSERT_EQ(static_cast<int>(path.size()), cfg.window + 1);
    EXPECT_EQ(path[0], pos[i]);
    EXPECT_TRUE(is_walk(g, path));
    EXPECT_EQ(dist.get(goals[i][0], path.back()), dist.get(goals[i][0], pos[i]) - cfg.window);
  }
  EXPECT_EQ(banded.searches(), 2);
}

TEST(GdRhcrProduct, StepBudgetIsHonouredByCounting) {
  // A budget no solve can fit: every primary solve is skipped and counted, guidance is cut
  // short, the secondary solver moves everyone, and the run stays collision-free and moving.
  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  GdRhcrConfig cfg = product_budget_config();
  cfg.step_budget_s = 1e-9;
  GdRhcrPlanner p(g, 300, 4, cfg);
  RandomNavigationStream tasks(g, 4);
  SimResult r = run(g, tasks, p, random_starts(g, 300, 4), 40);
  EXPECT_GT(r.goals_reached, 0);
  const auto s = p.stats();
  EXPECT_GT(s["budget_skips"].get<long>(), 0);
  EXPECT_EQ(s["budget_skips"].get<long>(), s["primary_calls"].get<long>());
  EXPECT_EQ(s["guidance_cut_short"].get<long>(), 40);
  // Without a budget the same run solves groups with PBS and never skips.
  GdRhcrPlanner q(g, 300, 4, product_budget_config());
  RandomNavigationStream tasks2(g, 4);
  run(g, tasks2, q, random_starts(g, 300, 4), 40);
  EXPECT_EQ(q.stats()["budget_skips"].get<long>(), 0);
  EXPECT_GT(q.stats()["primary_calls"].get<long>(), 0);
  cfg.step_budget_s = -1;
  EXPECT_THROW(GdRhcrPlanner(g, 10, 1, cfg), ParamError);
}

TEST(LocalGuidance, LazyKeepsAValidPathEagerSearchesEveryStep) {
  // Alone on an open map, far from its goal: after one step along its path, a lazy guidance
  // keeps the path (still valid, meets nobody); an eager one searches again every step.
  Grid g = Grid::load(repo("maps/empty-48-48.map"));
  DistTable dist(g);
  for (bool lazy : {true, false}) {
    LocalGuidanceConfig cfg;
    cfg.lazy = lazy;
    LocalGuidance lg(g, 1, cfg);
    std::vector<Cell> pos = {g.cell(0, 0)};
    std::vector<std::vector<Cell>> goals = {{g.cell(47, 47)}};
    WorldView w0{g, dist, 0, pos, goals};
    lg.update(w0, {0});
    EXPECT_EQ(lg.searches(), 1);
    pos[0] = lg.next_cell(0, 0, pos[0]);
    WorldView w1{g, dist, 1, pos, goals};
    lg.update(w1, {0});
    EXPECT_EQ(lg.searches(), lazy ? 1 : 2) << (lazy ? "lazy" : "eager");
    EXPECT_EQ(lg.kept(), lazy ? 1 : 0);
    const auto path = lg.path_from(0, 1);
    ASSERT_FALSE(path.empty());
    EXPECT_EQ(path[0], pos[0]);
    EXPECT_TRUE(is_walk(g, path));
  }
}

// The product default plans guidance 30 steps ahead on maps without many cut cells, up to 2,000
// agents (20 where the motion forecast runs, for the paper preset with guidance switched on, for
// guided PIBT and for fleets of thousands); a warehouse run with
// it is collision-free (the simulator validates every step), every agent moves, goals are
// reached, and it is the same run with 1 and 2 threads (budget mode).
TEST(GdRhcrProduct, DefaultGuidanceWindowIs30WithoutCutCellsUpTo2000Agents) {
  auto window_of = [](const std::string& planner, int agents, const std::string& preset,
                      const std::string& map = "warehouse-10-20-10-2-1.map") {
    Grid g = Grid::load(repo("maps/" + map));
    Params p;
    p.set("preset", preset);
    p.set("guidance", "local");
    return make_planner(planner, p, g, agents, 1)->params()["lg_window"].get<int>();
  };
  EXPECT_EQ(window_of("gd-rhcr", 400, "default"), 30);
  EXPECT_EQ(window_of("gd-rhcr", 2500, "default"), 20);
  EXPECT_EQ(window_of("gd-rhcr", 400, "paper"), 20);
  EXPECT_EQ(window_of("pibt", 400, "default"), 20);
  EXPECT_EQ(window_of("gd-rhcr", 400, "default", "empty-48-48.map"), 30);
  EXPECT_EQ(window_of("gd-rhcr", 300, "default", "random-32-32-20.map"), 20);  // cut cells: the forecast's maps

  // The collision cost is paid per kind of conflict, for fleets of thousands too.
  auto per_kind = [](int agents, const std::string& planner) {
    Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
    Params p;
    p.set("guidance", "local");
    return make_planner(planner, p, g, agents, 1)->params()["lg_cost_per_kind"].get<bool>();
  };
  EXPECT_TRUE(per_kind(400, "gd-rhcr"));
  EXPECT_TRUE(per_kind(400, "pibt"));
  EXPECT_TRUE(per_kind(2500, "gd-rhcr"));
  // Conflicts far ahead cost less where the motion forecast runs (maps with many cut cells).
  auto far_cost = [](const std::string& map) {
    Grid g = Grid::load(repo("maps/" + map));
    Params p;
    return make_planner("gd-rhcr", p, g, 300, 1)->params()["lg_far_cost"].get<double>();
  };
  EXPECT_EQ(far_cost("random-32-32-20.map"), 2.0);
  EXPECT_EQ(far_cost("warehouse-10-20-10-2-1.map"), -1.0);
  // The contraflow cost is the product's: not the paper preset's, not the PIBT baseline's.
  auto contraflow = [](const std::string& planner, const std::string& preset, int agents) {
    Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
    Params p;
    p.set("preset", preset);
    p.set("guidance", "local");
    return make_planner(planner, p, g, agents, 1)->params()["lg_contraflow"].get<double>();
  };
  EXPECT_EQ(contraflow("gd-rhcr", "default", 400), 0.1);
  EXPECT_EQ(contraflow("gd-rhcr", "default", 2500), 0.1);
  EXPECT_EQ(contraflow("gd-rhcr", "paper", 400), 0.0);
  EXPECT_EQ(contraflow("pibt", "default", 400), 0.0);

  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  std::vector<std::vector<Cell>> first;
  for (const char* threads : {"1", "2"}) {  // budget mode: the same run for any thread count
    Params p;
    p.set("node-budget", "200");
    p.set("threads", threads);
    auto planner = make_planner("gd-rhcr", p, g, 300, 5);
    RandomNavigationStream tasks(g, 5);
    SimResult r = run(g, tasks, *planner, random_starts(g, 300, 5), 80);
    EXPECT_GT(r.goals_reached, 100);
    for (size_t i = 0; i < r.paths.size(); ++i) {
      std::vector<Cell> visited(r.paths[i].begin(), r.paths[i].end());
      std::sort(visited.begin(), visited.end());
      EXPECT_GT(std::unique(visited.begin(), visited.end()) - visited.begin(), 1) << "agent " << i << " never moved";
    }
    if (first.empty()) first = r.paths;
    else EXPECT_EQ(r.paths, first) << threads << " threads";
  }
}
