// Every planner on every map in maps/ in both action models (issue 23): short runs with a few
// agents, every step validated by the simulator in the model in force (a violation throws
// CollisionError and fails the test), and the fleet makes progress. Planners that do not plan in
// the rotation model must refuse it (action_model_test.cpp); the ones that do are run here.
#include <gtest/gtest.h>

#include <dirent.h>

#include <algorithm>

#include "gdrhcr/planner.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

std::vector<std::string> standard_maps() {
  std::vector<std::string> maps;
  if (DIR* d = opendir(repo("maps").c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string name = e->d_name;
      if (name.size() > 4 && name.compare(name.size() - 4, 4, ".map") == 0) maps.push_back(name);
    }
    closedir(d);
  }
  std::sort(maps.begin(), maps.end());
  return maps;
}

// Runs `planner` for `steps` steps with `agents` agents and checks that the fleet moved: at least
// half the agents left their start cell.
void run_valid(const std::string& planner, const std::string& map, ActionModel model, int agents, int steps,
               Params none = {}) {
  SCOPED_TRACE(planner + " on " + map + " in " + action_model_name(model));
  const Grid g = Grid::load(repo("maps/" + map));
  DistTable dist(g, model);
  RandomNavigationStream tasks(g, 7);
  const auto starts = random_starts(g, agents, 7);
  auto p = make_planner(planner, none, g, agents, 7, model);
  SimOptions opt;
  opt.steps = steps;
  opt.record_paths = true;
  opt.action_model = model;
  const SimResult r = run_simulation(g, dist, tasks, *p, starts, opt);
  EXPECT_EQ(r.collisions, 0);
  int moved = 0;
  for (const auto& path : r.paths)
    moved += std::any_of(path.begin(), path.end(), [&](Cell c) { return c != path.front(); });
  EXPECT_GE(moved, agents / 2) << "the fleet hardly moved";
  EXPECT_LE(r.throughput, r.free_flow_throughput + 1e-9);
}
}  // namespace

TEST(RotationPlanners, EveryPlannerIsValidOnEveryMapInBothModels) {
  const auto maps = standard_maps();
  ASSERT_GE(maps.size(), 10u);
  for (const std::string& planner : planner_names())
    for (ActionModel model : {ActionModel::kMapf, ActionModel::kRotation}) {
      if (!planner_supports(planner, model)) continue;
      for (const std::string& map : maps) run_valid(planner, map, model, 24, 40);
    }
}

TEST(RotationPlanners, PlannersThatTurnStayValidWhenCrowded) {
  for (const std::string& planner : planner_names()) {
    if (!planner_supports(planner, ActionModel::kRotation)) continue;
    Params budget;  // PBS stops after a fixed number of nodes (falling back), whatever the machine
    if (planner != "pibt") budget.set("node-budget", "3000");
    run_valid(planner, "random-32-32-20.map", ActionModel::kRotation, 250, 60, budget);
    run_valid(planner, "warehouse-10-20-10-2-1.map", ActionModel::kRotation, 400, 40, budget);
  }
}

TEST(RotationPlanners, GuidedPibtWithForecastTurnsValidly) {
  for (const char* map : {"random-32-32-20.map", "room-32-32-4.map", "warehouse-10-20-10-2-1.map"}) {
    Params guided;
    guided.set("guidance", "local");
    guided.set("lg-forecast", "8");
    run_valid("pibt", map, ActionModel::kRotation, 120, 40, guided);
  }
}
