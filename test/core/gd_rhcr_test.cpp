// GD-RHCR (Algorithm 1): lazy reuse, soft constraints, determinism across thread counts, and
// zero collisions on every shipped map at low and high density, for V below and above 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "gdrhcr/gd_rhcr.hpp"
#include "preset_config.hpp"
#include "gdrhcr/simulator.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

// The paper's configuration (most tests); product_budget_config() is the product default.
GdRhcrConfig budget_config() {
  GdRhcrConfig c = preset_config("paper");
  c.node_budget = 200;     // deterministic: no dependence on the machine's speed
  c.timeout_s = 1e6;
  return c;
}

SimResult simulate(const Grid& g, TaskStream& tasks, GdRhcrPlanner& p, int agents, int steps,
                   uint64_t seed, bool paths = false) {
  DistTable dist(g);
  SimOptions opt;
  opt.steps = steps;
  opt.record_paths = paths;
  return run_simulation(g, dist, tasks, p, random_starts(g, agents, seed), opt);
}
}  // namespace

TEST(GdRhcr, LoneGroupReusesItsPlanUntilExhausted) {
  // One agent with a distant goal on an empty map: solved at t = 0, then the cached plan is
  // followed until its H-step window runs out (t = H, 2H, ...), never in between.
  Grid g = Grid::load(repo("maps/empty-48-48.map"));
  DistTable dist(g);
  GdRhcrConfig cfg = budget_config();
  cfg.H = 5;
  GdRhcrPlanner p(g, 1, 1, cfg);
  std::vector<Cell> pos = {g.cell(0, 0)};
  std::vector<std::vector<Cell>> goals = {{g.cell(47, 47)}};
  std::vector<Cell> next(1);
  for (int t = 0; t < 20; ++t) {
    WorldView w{g, dist, t, pos, goals};
    p.plan_step(w, next);
    ASSERT_EQ(p.last_groups().size(), 1u);
    const GroupAction expected = (t % 5 == 0) ? GroupAction::Primary : GroupAction::Reused;
    EXPECT_EQ(p.last_groups()[0].action, expected) << "t=" << t;
    EXPECT_EQ(dist.get(goals[0][0], next[0]), dist.get(goals[0][0], pos[0]) - 1);  // optimal
    pos = next;
  }
  EXPECT_EQ(p.stats()["primary_calls"], 4);
  EXPECT_EQ(p.stats()["cache_reuses"], 16);
}

// Planner::intended_next (the executor's catch-up): after a step, the cell after the agent's new
// cell on its plan, one step further on; kNoCell for a cell off its plan. With the paper's
// configuration (no guidance) from the cached plan, with the product's from the guidance path.
TEST(GdRhcr, IntendsTheNextCellOfItsPlanAfterAStep) {
  Grid g = Grid::from_rows({"..........", "..........", ".........."});
  DistTable dist(g);
  for (const char* preset : {"paper", "default"}) {
    GdRhcrConfig cfg = preset_config(preset);
    cfg.node_budget = 200;
    cfg.timeout_s = 1e6;
    GdRhcrPlanner p(g, 1, 1, cfg);
    std::vector<Cell> pos = {g.cell(0, 1)};
    std::vector<std::vector<Cell>> goals = {{g.cell(9, 1)}};
    std::vector<Cell> next(1);
    for (int t = 0; t < 4; ++t) {
      WorldView w{g, dist, t, pos, goals};
      p.plan_step(w, next);
      const Cell then = p.intended_next(0, next[0]);
      ASSERT_NE(then, kNoCell) << preset << " t=" << t;
      EXPECT_TRUE(g.step_allowed(next[0], then)) << preset;
      EXPECT_EQ(dist.get(goals[0][0], then), dist.get(goals[0][0], next[0]) - 1) << preset << ": on to the goal";
      EXPECT_EQ(p.intended_next(0, g.cell(5, 0)), kNoCell) << preset << ": a cell off the plan";
      pos = next;
    }
  }
}

TEST(GdRhcr, JoiningAgentTriggersReplan) {
  // Two agents approach each other head-on; when they come within V they form one group with
  // plans from different solves, so that group replans at once.
  Grid g = Grid::from_rows({"..............", "..............", ".............."});
  DistTable dist(g);
  GdRhcrConfig cfg = budget_config();
  cfg.k_threshold = 10;  // a pair stays with the primary solver
  GdRhcrPlanner p(g, 2, 1, cfg);
  std::vector<Cell> pos = {g.cell(0, 1), g.cell(13, 1)};
  std::vector<std::vector<Cell>> goals = {{g.cell(13, 1)}, {g.cell(0, 1)}};
  std::vector<Cell> next(2);
  bool joined = false;
  for (int t = 0; t < 8 && !joined; ++t) {
    WorldView w{g, dist, t, pos, goals};
    p.plan_step(w, next);
    if (p.last_groups().size() == 1) {
      joined = true;
      EXPECT_EQ(p.last_groups()[0].action, GroupAction::Primary) << "t=" << t;
    }
    pos = next;
  }
  EXPECT_TRUE(joined);
}

TEST(GdRhcr, SoftConstraintsChangeThePlan) {
  // Agent 1 waits on the top lane (its goal is where it stands), 5 cells from agent 0 (> V,
  // so another group). Agent 0's shortest route runs through it; the detour along the bottom
  // lane is 4 steps longer. A cheap conflict (c_soft = 1) is accepted; a costly one
  // (c_soft = 10) is avoided by the detour.
  Grid g = Grid::from_rows({"..........", ".@@@@@@@@.", ".........."});
  DistTable dist(g);
  const Cell blocker = g.cell(5, 0);
  auto first_plan_of_agent0 = [&](double c_soft) {
    GdRhcrConfig cfg = budget_config();
    cfg.c_soft = c_soft;
    GdRhcrPlanner p(g, 2, 1, cfg);
    std::vector<Cell> pos = {g.cell(0, 0), blocker};
    std::vector<std::vector<Cell>> goals = {{g.cell(9, 0)}, {blocker}};
    std::vector<Cell> next(2);
    WorldView w{g, dist, 0, pos, goals};
    p.plan_step(w, next);
    EXPECT_EQ(p.last_groups().size(), 2u);
    return p.planned_path(0);
  };
  auto cheap = first_plan_of_agent0(1.0);
  auto costly = first_plan_of_agent0(10.0);
  EXPECT_NE(std::find(cheap.begin(), cheap.end(), blocker), cheap.end());
  EXPECT_EQ(std::find(costly.begin(), costly.end(), blocker), costly.end());
  EXPECT_NE(std::find(costly.begin(), costly.end(), g.cell(5, 2)), costly.end());  // bottom lane
}

TEST(GdRhcr, IdenticalResultsAcrossThreadCounts) {
  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  std::vector<std::vector<std::vector<Cell>>> runs;
  std::vector<nlohmann::json> stats;
  for (int threads : {1, 2, 4}) {
    GdRhcrConfig cfg = budget_config();
    cfg.threads = threads;
    GdRhcrPlanner p(g, 300, 5, cfg);
    MapdCells cells = default_mapd_cells(g);
    PickupDeliveryStream tasks(g, cells.pickups, cells.deliveries, 5);
    runs.push_back(simulate(g, tasks, p, 300, 80, 5, true).paths);
    auto s = p.stats();
    s.erase("primary_time_mean_s");
    s.erase("plan_time_mean_all_steps_s");
    stats.push_back(s);
  }
  EXPECT_EQ(runs[0], runs[1]);
  EXPECT_EQ(runs[0], runs[2]);
  EXPECT_EQ(stats[0], stats[1]);
  EXPECT_GT(stats[0]["primary_calls"].get<long>(), 0);
}

TEST(GdRhcr, RejectsNonsenseParameters) {
  Grid g = Grid::from_rows({"...."});
  auto make = [&](auto tweak) {
    GdRhcrConfig c;
    tweak(c);
    return GdRhcrPlanner(g, 1, 1, c);
  };
  EXPECT_THROW(make([](GdRhcrConfig& c) { c.V = -1; }), ParamError);
  EXPECT_THROW(make([](GdRhcrConfig& c) { c.H = 0; }), ParamError);
  EXPECT_THROW(make([](GdRhcrConfig& c) { c.c_soft = -1; }), ParamError);
  EXPECT_THROW(make([](GdRhcrConfig& c) { c.threads = 0; }), ParamError);
  EXPECT_THROW(make([](GdRhcrConfig& c) { c.solver = "cbs"; }), ParamError);
}

TEST(GdRhcr, DefaultThresholdFollowsThePaper) {
  Grid g = Grid::from_rows({"...."});
  EXPECT_EQ(GdRhcrPlanner(g, 800, 1, GdRhcrConfig{}).k_threshold(), 20);
  EXPECT_EQ(GdRhcrPlanner(g, 150, 1, GdRhcrConfig{}).k_threshold(), 15);
  EXPECT_EQ(GdRhcrPlanner(g, 5, 1, GdRhcrConfig{}).k_threshold(), 2);
}

std::vector<std::string> shipped_maps();

// Zero collisions (the simulator throws on any) on every shipped map, low and high density.
class GdRhcrMaps : public ::testing::TestWithParam<std::string> {};

TEST(GdRhcrMapsList, CoversEveryShippedMap) { EXPECT_GE(shipped_maps().size(), 13u); }

TEST_P(GdRhcrMaps, NoCollisionsLowAndHighDensity) {
  Grid g = Grid::load(repo("maps/" + GetParam()));
  const int free_cells = static_cast<int>(g.free_cells().size());
  for (double density : {0.03, 0.25}) {
    // At most 1000 agents: the large maps (up to 70,000 cells) stay quick; 10,000-agent fleets
    // are covered by the scale benchmark, not by unit tests.
    const int agents = std::clamp(static_cast<int>(density * free_cells), 2, 1000);
    GdRhcrPlanner p(g, agents, 3, budget_config());
    RandomNavigationStream tasks(g, 3);
    SimResult r = simulate(g, tasks, p, agents, 60, 3);
    EXPECT_EQ(r.collisions, 0);
    EXPECT_GT(r.goals_reached, 0) << GetParam() << " density " << density;
  }
}

// Every map shipped in maps/ (MovingAI, kiva and the generated ones).
std::vector<std::string> shipped_maps() {
  std::vector<std::string> names;
  for (auto& e : std::filesystem::directory_iterator(repo("maps")))
    if (e.path().extension() == ".map") names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

INSTANTIATE_TEST_SUITE_P(AllMaps, GdRhcrMaps, ::testing::ValuesIn(shipped_maps()),
                         [](const auto& info) {
                           std::string s = info.param.substr(0, info.param.size() - 4);
                           std::replace(s.begin(), s.end(), '-', '_');
                           return s;
                         });

TEST(GdRhcr, SmallVisibilityIsKeptSafeByTheFinalCheck) {
  // V < 2 gives no Dependence-Time guarantee: groups one cell apart may plan into each other.
  // The final check must repair every such step.
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  long repairs = 0;
  for (int V : {0, 1}) {
    GdRhcrConfig cfg = budget_config();
    cfg.V = V;
    GdRhcrPlanner p(g, 200, 7, cfg);
    RandomNavigationStream tasks(g, 7);
    SimResult r = simulate(g, tasks, p, 200, 80, 7);
    EXPECT_GT(r.goals_reached, 0);
    repairs += p.stats()["repairs"].get<long>();
  }
  EXPECT_GT(repairs, 0);  // the check really had work to do
}

TEST(GdRhcr, LargeGroupsUseTheSecondarySolver) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  GdRhcrConfig cfg = budget_config();
  cfg.k_threshold = 3;
  GdRhcrPlanner p(g, 300, 2, cfg);
  RandomNavigationStream tasks(g, 2);
  simulate(g, tasks, p, 300, 30, 2);
  EXPECT_GT(p.stats()["threshold_fallbacks"].get<long>(), 0);
  EXPECT_GT(p.stats()["primary_calls"].get<long>(), 0);
}

// Two agents in one cell is input no step can fix: plan_step says so instead of repairing for
// ever (it used to loop in repair_step; the ROS node's planner worker would never return).
TEST(GdRhcr, TwoAgentsInOneCellIsAnErrorNotAHang) {
  Grid g = Grid::from_rows({"@.@", "@@@"});
  DistTable dist(g);
  for (GdRhcrConfig c : {preset_config("paper"), preset_config("default")}) {
    GdRhcrPlanner p(g, 2, 1, c);
    std::vector<Cell> pos = {g.cell(1, 0), g.cell(1, 0)};
    std::vector<std::vector<Cell>> goals = {{g.cell(1, 0)}, {g.cell(1, 0)}};
    WorldView w{g, dist, 0, pos, goals};
    std::vector<Cell> next(2, kNoCell);
    try {
      p.plan_step(w, next);
      ADD_FAILURE() << "no error";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("no collision-free step"), std::string::npos) << e.what();
    }
  }
}

// The product default's density rule: a lone agent with nobody near is planned by PBS; a
// group whose neighbourhood (the bounding box grown by density_margin cells) holds agents on
// more than 2% of its free cells goes to guided PIBT, even when it is small. Here two agents
// side by side fill 2 of the 90 cells around them (2.2%; primary under the former 5% rule).
TEST(GdRhcrProduct, DensityRuleKeepsPbsForLoneAgentsOnly) {
  std::vector<std::string> rows(21, std::string(21, '.'));
  Grid g = Grid::from_rows(rows);
  DistTable dist(g);
  GdRhcrConfig c = preset_config("default");
  c.k_threshold = 5;  // the size rule sends neither group to PIBT
  c.node_budget = 200;
  GdRhcrPlanner p(g, 3, 1, c);
  const std::vector<Cell> pos = {g.cell(5, 10), g.cell(15, 10), g.cell(16, 10)};
  const std::vector<std::vector<Cell>> goals = {{g.cell(5, 2)}, {g.cell(15, 18)}, {g.cell(16, 2)}};
  std::vector<Cell> next(3, kNoCell);
  WorldView w{g, dist, 0, pos, goals};
  p.plan_step(w, next);
  ASSERT_EQ(p.last_groups().size(), 2u);
  for (const auto& info : p.last_groups()) {
    if (info.agents.size() == 1) EXPECT_EQ(info.action, GroupAction::Primary) << "the lone agent";
    else EXPECT_EQ(info.action, GroupAction::ThresholdFallback) << "the pair";
  }
  for (int i = 0; i < 3; ++i) EXPECT_LT(dist.get(goals[i][0], next[i]), dist.get(goals[i][0], pos[i]));
}

