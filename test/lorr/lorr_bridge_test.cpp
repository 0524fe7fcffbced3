// The Start-Kit adapter's core side (lorr_adapter/lorr_bridge.hpp), driven as the Start-Kit
// drives it but without the Start-Kit: every cell's distance row before the first step when they
// fit, else the rows' warm-up within a budget, and rows the distance table evicted computed
// again before the planner's step, not inside it.
#include "lorr_bridge.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/grid.hpp"

namespace {

using gdrhcr::Action;
using gdrhcr::Grid;
using gdrhcr::Pose;
using gdrhcr_lorr::Bridge;
using gdrhcr_lorr::BridgeOptions;

constexpr int kWait = 3;  // the Start-Kit's W

// The Start-Kit's map: 1 for a blocked cell, row-major like our cells.
std::vector<int> start_kit_map(const Grid& g) {
  std::vector<int> map(g.num_cells());
  for (int c = 0; c < g.num_cells(); ++c) map[c] = g.is_free(c) ? 0 : 1;
  return map;
}

Action our_action(int a) {
  switch (a) {
    case 0: return Action::kForward;
    case 1: return Action::kClockwise;
    case 2: return Action::kCounterClockwise;
    default: return Action::kWait;
  }
}

Grid load(const std::string& name) { return Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/" + name); }

// Twenty agents on random-32-32-20 at its first free cells, facing east, each with a goal far off.
struct SmallFleet {
  static constexpr int n = 20;
  Grid g = load("random-32-32-20.map");
  std::vector<int> pos = std::vector<int>(n), head = std::vector<int>(n, 0);
  std::vector<std::vector<int>> goals = std::vector<std::vector<int>>(n);
  SmallFleet() {
    const auto& free = g.free_cells();
    for (int i = 0; i < n; ++i) pos[i] = free[i], goals[i] = {free[free.size() - 1 - 7 * i]};
  }
  // With `dist_mb` of rows: the default holds every free cell's row (computed before the first
  // step); 1 MB holds the goals' rows but not every cell's, so rows come as goals do.
  Bridge bridge(double budget_ms, int dist_mb = BridgeOptions{}.dist_budget_mb) const {
    BridgeOptions o;
    o.budget_ms = budget_ms;
    o.dist_budget_mb = dist_mb;
    return Bridge(g.height(), g.width(), start_kit_map(g), n, o);
  }
  // Steps [from, to] as the Start-Kit would, each checked: free cells, no two agents in one.
  // Returns the forward moves made; the first step's actions go to `first` if given.
  int run(Bridge& bridge, int from, int to, std::vector<int>* first = nullptr) {
    std::vector<int> actions;
    int forward = 0;
    for (int t = from; t <= to; ++t) {
      bridge.plan(t, 1.0, pos, head, goals, actions);
      if (first && t == from) *first = actions;
      EXPECT_EQ(static_cast<int>(actions.size()), n);
      std::set<int> cells;
      for (int i = 0; i < n; ++i) {
        forward += actions[i] == 0;
        const Pose p = gdrhcr::apply_action(g, Pose{pos[i], static_cast<gdrhcr::Heading>(head[i])}, our_action(actions[i]));
        EXPECT_TRUE(g.is_free(p.cell)) << "agent " << i << " at step " << t;
        pos[i] = p.cell, head[i] = p.heading;
        EXPECT_TRUE(cells.insert(pos[i]).second) << "two agents in cell " << pos[i] << " after step " << t;
      }
    }
    return forward;
  }
};

TEST(LorrBridge, WhenEveryCellsRowFitsTheRowsComeBeforeTheFirstStepAndItMoves) {
  SmallFleet f;
  Bridge bridge = f.bridge(100);
  EXPECT_EQ(bridge.stats().rows_precomputed, f.g.free_cells().size());
  std::vector<int> first;
  f.run(bridge, 0, 0, &first);
  EXPECT_NE(first, std::vector<int>(f.n, kWait)) << "the first step turns or moves agents: no warm-up";
  EXPECT_GT(f.run(bridge, 1, 30), f.n);
  const auto s = bridge.stats();
  EXPECT_EQ(s.warm_up_steps, 0);
  EXPECT_EQ(s.rows_before_planning, 0u);
  EXPECT_EQ(s.rows_in_planner, 0u);
}

TEST(LorrBridge, TheWorldsRowsHaveTheStepCostsOfThePlannersBudget) {
  // Shelves with one-cell aisles and a band two rows high beside them (an open area, lanes.hpp),
  // filled past 90% of its free cells: PIBT plans over operations when the step budget leaves
  // room for them (auto), and then a move along the band costs 2 more (rule operations). The
  // rule reads the budget the adapter gives the planner, and the rows are made with the same one.
  const Grid g = Grid::from_rows({"............", ".@@@@@@@@@@.", "............", ".@@@@@@@@@@.",
                                  "............", ".@@@@@@@@@@.", "............", "@@@@@@@@@@@@",
                                  "............", "............"});
  const int n = static_cast<int>(g.free_cells().size()) * 92 / 100;
  auto costs = [&](double budget_ms) {
    BridgeOptions o;
    o.budget_ms = budget_ms;
    return Bridge(g.height(), g.width(), start_kit_map(g), n, o).step_costs();
  };
  EXPECT_EQ(costs(100).open, 2.0) << "a budget with room for operations";
  EXPECT_EQ(costs(100).lane, 2.0);
  EXPECT_EQ(costs(0).open, 0.0) << "no budget: auto does not expect operations";
}

TEST(LorrBridge, ThePlannersCountersGoToStandardErrorEveryFewHundredSteps) {
  // The Start-Kit ends with _exit, so the planner's counters (how many steps planned over
  // operations, ...) are written as they stand every kStatsEvery steps: one line after the last
  // step of each such run of steps, its JSON whole.
  SmallFleet f;
  Bridge bridge = f.bridge(0);
  testing::internal::CaptureStderr();
  f.run(bridge, 0, gdrhcr_lorr::kStatsEvery - 2);
  const std::string before = testing::internal::GetCapturedStderr();
  EXPECT_EQ(before.find("planner stats"), std::string::npos) << before;
  testing::internal::CaptureStderr();
  f.run(bridge, gdrhcr_lorr::kStatsEvery - 1, gdrhcr_lorr::kStatsEvery - 1);
  const std::string line = testing::internal::GetCapturedStderr();
  const std::string tag = "timestep " + std::to_string(gdrhcr_lorr::kStatsEvery - 1) + ": planner stats ";
  const size_t at = line.find(tag);
  ASSERT_NE(at, std::string::npos) << line;
  const auto stats = nlohmann::json::parse(line.substr(at + tag.size()));
  EXPECT_TRUE(stats.contains("secondary_operation_calls")) << stats.dump();
  EXPECT_GT(stats.at("steps_with_a_solve").get<long>(), 0) << stats.dump();
}

TEST(LorrBridge, WithABudgetTheWarmUpWaitsOnceThenTheFleetMovesWithoutCollisions) {
  SmallFleet f;
  Bridge bridge = f.bridge(100, 1);
  EXPECT_EQ(bridge.stats().rows_precomputed, 0u) << "every cell's row does not fit in 1 MB";
  std::vector<int> actions;
  bridge.plan(0, 1.0, f.pos, f.head, f.goals, actions);
  EXPECT_EQ(actions, std::vector<int>(f.n, kWait)) << "the step that computes the rows is all waits";
  EXPECT_EQ(bridge.stats().warm_up_steps, 1);
  EXPECT_GT(f.run(bridge, 1, 30), f.n);
  EXPECT_EQ(bridge.stats().warm_up_steps, 1);
  EXPECT_EQ(bridge.stats().steps, 31);
}

TEST(LorrBridge, HoweverShortTheBudgetRowsKeepComingAndTheWarmUpEnds) {
  // A budget far too short for any row: one batch of rows per step still comes.
  SmallFleet f;
  Bridge bridge = f.bridge(0.001, 1);
  std::vector<int> actions;
  for (int t = 0; t < 15; ++t) bridge.plan(t, 1.0, f.pos, f.head, f.goals, actions);
  const auto s = bridge.stats();
  EXPECT_GE(s.warm_up_steps, 1);
  EXPECT_LT(s.warm_up_steps, 15) << "the 20 goals' rows, a batch per step";
  EXPECT_GE(s.rows_before_planning, static_cast<uint64_t>(SmallFleet::n));
  EXPECT_EQ(s.rows_in_planner, 0u);
}

// The preparation (GDRHCR_PREP_DIR) runs its trials as the run will plan: at the planner's share
// of the budget, so the anytime search runs in them; every candidate cost on two seeds. A short
// preprocessing limit keeps the trials short.
TEST(LorrBridge, ThePreparationsTrialsRunAtTheRunsBudget) {
  SmallFleet f;
  const std::string dir = ::testing::TempDir() + "lorr_prep_budget";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  BridgeOptions o;
  o.budget_ms = 100;
  o.prep_dir = dir;
  o.preprocess_s = 3;
  Bridge bridge(f.g.height(), f.g.width(), start_kit_map(f.g), f.n, o);
  std::vector<std::filesystem::path> files;
  for (auto& e : std::filesystem::directory_iterator(dir)) files.push_back(e.path());
  ASSERT_EQ(files.size(), 1u);
  std::ifstream in(files[0]);
  const auto prep = nlohmann::json::parse(in);
  EXPECT_NEAR(prep.at("step_budget_s").get<double>(), 0.093, 1e-9);
  EXPECT_EQ(prep.at("trials").size(), 6u) << "traffic costs 0, 1 and 2 on two seeds";
  EXPECT_GT(f.run(bridge, 0, 5), 0);
  std::filesystem::remove_all(dir);
}

TEST(LorrBridge, ARowTheTableEvictedIsComputedAgainBeforeThePlannersStep) {
  // A 1 MB table holds a few dozen rows of this map; 200 goals come round again and again.
  const Grid g = load("warehouse-10-20-10-2-1.map");
  const int n = 10, distinct = 200;
  const auto& free = g.free_cells();
  std::vector<int> pos(n), head(n, 0), targets(distinct);
  for (int i = 0; i < n; ++i) pos[i] = free[37 * i];
  for (int k = 0; k < distinct; ++k) targets[k] = free[(free.size() / distinct) * k + 3];
  BridgeOptions o;
  o.dist_budget_mb = 1;
  Bridge bridge(g.height(), g.width(), start_kit_map(g), n, o);
  std::vector<int> actions;
  std::vector<std::vector<int>> goals(n);
  for (int t = 0; t < 3 * distinct / n; ++t) {
    for (int i = 0; i < n; ++i) goals[i] = {targets[(t * n + i) % distinct]};
    bridge.plan(t, 1.0, pos, head, goals, actions);
  }
  const auto s = bridge.stats();
  EXPECT_GT(s.evictions, 0u);
  EXPECT_GT(s.rows_before_planning, static_cast<uint64_t>(distinct)) << "evicted rows computed again";
  EXPECT_EQ(s.rows_in_planner, 0u);
}

// The rows' memory: unset, GDRHCR_DIST_MB keeps to three quarters of the memory available, so a
// machine without the 6.4 GB of Paris's rows computes rows as goals come instead of running out
// of memory; set, it is what it says, and nonsense is named.
TEST(LorrBridge, TheRowsMemoryKeepsWithinTheMemoryAvailableUnlessGiven) {
  using gdrhcr_lorr::default_dist_budget_mb;
  using gdrhcr_lorr::kDistBudgetMb;
  EXPECT_EQ(default_dist_budget_mb(0), kDistBudgetMb) << "memory unknown";
  EXPECT_EQ(default_dist_budget_mb(4000), 3000);
  EXPECT_EQ(default_dist_budget_mb(uint64_t(64) << 10), kDistBudgetMb);
  EXPECT_EQ(default_dist_budget_mb(1), 1);
  const uint64_t available = gdrhcr_lorr::available_memory_mb();
  EXPECT_GT(available, 0u) << "MemAvailable from /proc/meminfo";
  unsetenv("GDRHCR_DIST_MB");
  const int chosen = gdrhcr_lorr::bridge_options_from_env().dist_budget_mb;
  EXPECT_GE(chosen, 1);
  EXPECT_LE(chosen, kDistBudgetMb);
  EXPECT_LE(uint64_t(chosen), std::max<uint64_t>(1, available * 3 / 4 + 64)) << "within the memory available";
  setenv("GDRHCR_DIST_MB", "100", 1);
  EXPECT_EQ(gdrhcr_lorr::bridge_options_from_env().dist_budget_mb, 100);
  setenv("GDRHCR_DIST_MB", "lots", 1);
  try {
    gdrhcr_lorr::bridge_options_from_env();
    ADD_FAILURE() << "GDRHCR_DIST_MB=lots accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("GDRHCR_DIST_MB"), std::string::npos) << e.what();
  }
  unsetenv("GDRHCR_DIST_MB");
}

}  // namespace

TEST(LorrBridge, AOneOffOverrunIsForgottenAndARecurringOneIsPlannedFor) {
  // The first step runs 75 ms over (its allocations): the next steps are not planned for it. Steps
  // ending early plan for nothing. Two overruns within the window (over 1% of its steps) are: the
  // smaller of the two, until one of them leaves the window.
  using gdrhcr_lorr::OverrunMemory;
  OverrunMemory m;
  m.add(0.075);
  EXPECT_EQ(m.planned_s(), 0);
  for (int k = 0; k < 50; ++k) m.add(-0.002);
  EXPECT_EQ(m.planned_s(), 0);
  m.add(0.003);
  EXPECT_DOUBLE_EQ(m.planned_s(), 0.003);
  m.add(0.004);
  EXPECT_DOUBLE_EQ(m.planned_s(), 0.004);
  for (int k = 0; k < OverrunMemory::kWindow - 52; ++k) m.add(-0.001);  // the 75 ms leaves
  EXPECT_DOUBLE_EQ(m.planned_s(), 0.003);
  for (int k = 0; k < 51; ++k) m.add(-0.001);  // then the 3 ms: the 4 ms alone is forgotten
  EXPECT_EQ(m.planned_s(), 0);
}
