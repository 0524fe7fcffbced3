// The Planner interface's introspection (groups(), planned_path()), used by the ROS node for
// rviz through the base class: groups cover every agent once, a planned path starts at the
// agent's cell and continues with the step just planned.
#include <gtest/gtest.h>

#include <algorithm>

#include "gdrhcr/planner.hpp"
#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

struct Scenario {
  Grid grid = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist{grid};
  std::vector<Cell> pos = random_starts(grid, 30, 7);
  std::vector<std::vector<Cell>> goals;
  Scenario() {
    auto far = random_starts(grid, 30, 8);
    for (int i = 0; i < 30; ++i) goals.push_back({far[i]});
  }
};

std::unique_ptr<Planner> build(const std::string& name, const Grid& g) {
  Params p;
  if (name != "pibt") p.set("node-budget", "500");
  return make_planner(name, p, g, 30, 1);
}
}  // namespace

TEST(PlannerIntrospection, GdRhcrGroupsPartitionTheAgentsAndPathsStartAtTheirCells) {
  Scenario s;
  auto planner = build("gd-rhcr", s.grid);
  std::vector<Cell> next(s.pos.size());
  for (int t = 0; t < 5; ++t) {
    WorldView w{s.grid, s.dist, t, s.pos, s.goals};
    planner->plan_step(w, next);
    std::vector<int> seen(s.pos.size(), 0);
    for (auto& g : planner->groups()) {
      EXPECT_FALSE(g.solver.empty());
      for (int a : g.agents) ++seen[a];
    }
    EXPECT_TRUE(std::all_of(seen.begin(), seen.end(), [](int k) { return k == 1; })) << "t=" << t;
    for (int i = 0; i < static_cast<int>(s.pos.size()); ++i) {
      const auto path = planner->planned_path(i);  // moved by PIBT this step: that step alone
      ASSERT_GE(path.size(), 2u) << "agent " << i << " t=" << t;
      EXPECT_EQ(path[0], s.pos[i]) << "agent " << i << " t=" << t;
      EXPECT_EQ(path[1], next[i]) << "agent " << i << " t=" << t;
    }
    s.pos = next;
  }
}

TEST(PlannerIntrospection, RhcrPathsFollowItsWindowAndPibtHasNone) {
  Scenario s;
  auto rhcr = build("rhcr", s.grid);
  auto pibt = build("pibt", s.grid);
  std::vector<Cell> next(s.pos.size()), other(s.pos.size());
  int with_paths = 0;
  for (int t = 0; t < 7; ++t) {
    WorldView w{s.grid, s.dist, t, s.pos, s.goals};
    rhcr->plan_step(w, next);
    pibt->plan_step(w, other);
    EXPECT_TRUE(rhcr->groups().empty());
    EXPECT_TRUE(pibt->groups().empty());
    EXPECT_TRUE(pibt->planned_path(0).empty());
    for (int i = 0; i < static_cast<int>(s.pos.size()); ++i) {
      const auto path = rhcr->planned_path(i);
      if (path.empty()) continue;
      ++with_paths;
      EXPECT_EQ(path[0], s.pos[i]);
      if (path.size() >= 2) EXPECT_EQ(path[1], next[i]);
    }
    s.pos = next;
  }
  EXPECT_GT(with_paths, 0) << "PBS never produced a plan on 30 agents";
  EXPECT_TRUE(rhcr->planned_path(-1).empty());
  EXPECT_TRUE(rhcr->planned_path(30).empty());
}
