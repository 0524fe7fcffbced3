// PIBT on small maps: never a collision (the simulator validates every step and throws),
// goals get reached, and it copes with a narrow corridor and a crowded map.
#include <gtest/gtest.h>

#include "gdrhcr/pibt.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

// A task stream with fixed per-agent goal lists (cycled).
class ListStream : public TaskStream {
 public:
  explicit ListStream(std::vector<std::vector<Cell>> goals) : goals_(std::move(goals)), next_(goals_.size(), 0) {}
  std::string name() const override { return "list"; }
  Cell next_goal(int agent, Cell) override {
    auto& g = goals_[agent];
    return g[next_[agent]++ % g.size()];
  }
  std::unique_ptr<TaskStream> clone_fresh() const override { return std::make_unique<ListStream>(goals_); }

 private:
  std::vector<std::vector<Cell>> goals_;
  std::vector<size_t> next_;
};

SimResult run_pibt(const Grid& g, TaskStream& tasks, const std::vector<Cell>& starts, int steps,
                   uint64_t seed = 1) {
  DistTable dist(g);
  PibtPlanner planner(g, static_cast<int>(starts.size()), seed);
  SimOptions opt;
  opt.steps = steps;
  opt.record_paths = true;
  return run_simulation(g, dist, tasks, planner, starts, opt);
}
}  // namespace

TEST(Pibt, SingleAgentFollowsShortestPath) {
  Grid g = Grid::from_rows({".....", ".@@@.", "....."});
  ListStream tasks({{g.cell(4, 2), g.cell(0, 0)}});
  SimResult r = run_pibt(g, tasks, {g.cell(0, 0)}, 12);
  EXPECT_EQ(r.paths[0][6], g.cell(4, 2));  // 6 = the BFS distance
  EXPECT_EQ(r.goals_reached, 2);          // and back again by t = 12
  EXPECT_EQ(r.collisions, 0);
}

TEST(Pibt, HeadOnInOneLaneRingCorridor) {
  // A one-lane corridor closed into a ring (biconnected, where PIBT is complete): agents meet
  // head-on, the higher-priority one pushes the other back around the ring, and all arrive.
  Grid g = Grid::from_rows({".........", ".@@@@@@@.", "........."});
  ListStream tasks({{g.cell(8, 0), g.cell(0, 0)}, {g.cell(0, 0), g.cell(8, 0)}, {g.cell(0, 2), g.cell(8, 2)}});
  SimResult r = run_pibt(g, tasks, {g.cell(0, 0), g.cell(8, 0), g.cell(8, 2)}, 120);
  EXPECT_GE(r.goals_reached, 6);
}

TEST(Pibt, CrowdedSmallMapNoCollisionsAndProgress) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  for (uint64_t seed : {1, 2, 3}) {
    RandomNavigationStream tasks(g, seed);
    auto starts = random_starts(g, 300, seed);  // ~37% of the free cells
    SimResult r = run_pibt(g, tasks, starts, 200, seed);
    EXPECT_GT(r.goals_reached, 100) << seed;
    EXPECT_LE(r.throughput, r.free_flow_throughput);
  }
}

TEST(Pibt, WarehouseMapdManyAgents) {
  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  MapdCells cells = default_mapd_cells(g);
  PickupDeliveryStream tasks(g, cells.pickups, cells.deliveries, 4);
  auto starts = random_starts(g, 800, 4);
  SimResult r = run_pibt(g, tasks, starts, 150, 4);
  EXPECT_GT(r.throughput, 1.0);
  EXPECT_LE(r.throughput, r.free_flow_throughput);
}

TEST(Pibt, FullyPackedMapIsStillValid) {
  // Every cell of a one-lane corridor taken: nobody can move, waiting is the only legal step.
  Grid g = Grid::from_rows({"......"});
  RandomNavigationStream tasks(g, 1);
  SimResult r = run_pibt(g, tasks, random_starts(g, 6, 1), 20);
  EXPECT_EQ(r.goals_reached, 0);
}

TEST(Pibt, NearlyPackedMapStillMovesAgents) {
  Grid g = Grid::from_rows({"....", "....", "...."});
  RandomNavigationStream tasks(g, 2);
  SimResult r = run_pibt(g, tasks, random_starts(g, 11, 2), 200);
  EXPECT_GT(r.goals_reached, 20);
}

TEST(Pibt, SameSeedSameRun) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  RandomNavigationStream t1(g, 7), t2(g, 7);
  auto starts = random_starts(g, 100, 7);
  EXPECT_EQ(run_pibt(g, t1, starts, 100, 7).paths, run_pibt(g, t2, starts, 100, 7).paths);
}

// A planner that moves everyone onto agent 0's cell: the simulator must refuse the step.
class CollidingPlanner : public Planner {
 public:
  std::string name() const override { return "colliding"; }
  nlohmann::json params() const override { return {}; }
  StepReport plan_step(const WorldView& w, std::vector<Cell>& next) override {
    next = w.positions;
    next[1] = w.positions[0];
    return {};
  }
};

TEST(Simulator, CollisionIsAHardError) {
  Grid g = Grid::from_rows({"...."});
  DistTable dist(g);
  RandomNavigationStream tasks(g, 1);
  CollidingPlanner p;
  EXPECT_THROW(run_simulation(g, dist, tasks, p, {g.cell(0, 0), g.cell(1, 0)}, SimOptions{}),
               CollisionError);
}

TEST(Simulator, DuplicateStartsRejected) {
  Grid g = Grid::from_rows({"...."});
  DistTable dist(g);
  RandomNavigationStream tasks(g, 1);
  PibtPlanner p(g, 2, 1);
  EXPECT_THROW(run_simulation(g, dist, tasks, p, {g.cell(0, 0), g.cell(0, 0)}, SimOptions{}),
               CollisionError);
}

TEST(Simulator, FreeFlowMatchesSingleAgentRun) {
  // Alone, an agent following shortest paths achieves exactly the free-flow throughput.
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  RandomNavigationStream tasks(g, 11);
  SimResult r = run_pibt(g, tasks, random_starts(g, 1, 11), 300);
  EXPECT_DOUBLE_EQ(r.throughput, r.free_flow_throughput);
}
