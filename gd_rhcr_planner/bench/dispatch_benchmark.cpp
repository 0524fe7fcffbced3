// Batch against greedy dispatch in a closed loop without ROS (issue 14): the planner node's task
// bookkeeping (Fleet), a dispatcher and a core planner move a fleet on a map under full load
// (2 x robots tasks open, pickup and delivery drawn uniformly from the map's MAPD cells, the same
// seeded task sequence for every policy); robots execute every planned step. Prints deliveries
// per hour at the given tick rate, the mean distance from the robot to the pickup at assignment
// (robots about to finish count from their delivery, after it) and the dispatch time per tick.
// A benchmark (prints figures), not a test.
//   dispatch_benchmark --map maps/warehouse-10-20-10-2-1.map --robots 200 --steps 1200 --seeds 3
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "bench_options.hpp"
#include "gd_rhcr_planner/dispatcher.hpp"
#include "gd_rhcr_planner/fleet.hpp"
#include "gd_rhcr_planner/map_loader.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/task_stream.hpp"
#include "gdrhcr/validator.hpp"

using namespace gd_rhcr_planner;
using gdrhcr::Cell;

namespace {

struct Result {
  uint64_t delivered = 0;
  double empty_travel = 0;  // cells from the robot to the pickup at each assignment (moves included)
  uint64_t assignments = 0;
  double dispatch_s = 0, dispatch_max_s = 0;
  uint64_t reassigned = 0;
};

Result run(const LoadedMap& map, const gdrhcr::MapdCells& mapd, DispatchPolicy policy, const std::string& planner_name,
           int robots, int steps, uint64_t seed) {
  const auto& grid = map.grid;
  gdrhcr::DistTable dist(grid);
  Fleet fleet(grid, dist, robots);
  fleet.set_auto_assign(false);
  Dispatcher disp(policy, {});
  gdrhcr::Params params;
  auto planner = gdrhcr::make_planner(planner_name, params, grid, robots, seed);
  gdrhcr::StepValidator validator(grid);
  std::mt19937_64 rng(seed);
  // Robots on distinct random free cells.
  std::vector<Cell> free = grid.free_cells();
  std::shuffle(free.begin(), free.end(), rng);
  std::string err;
  for (int r = 0; r < robots; ++r) fleet.update_robot(r, grid.x_of(free[r]), grid.y_of(free[r]), false, false, err);
  std::mt19937_64 task_rng(seed * 7919 + 1);
  auto draw = [&](const std::vector<Cell>& v) { return v[task_rng() % v.size()]; };
  Result res;
  std::vector<Cell> pos, next;
  std::vector<std::vector<Cell>> goals;
  for (int t = 0; t < steps; ++t) {
    // Top up to 2 x robots open tasks (the soak's full load).
    size_t open = fleet.count_in_state(kQueued) + fleet.count_in_state(kAssigned) + fleet.count_in_state(kPicked);
    while (open < size_t(2 * robots)) {
      const Cell p = draw(mapd.pickups), d = draw(mapd.deliveries);
      if (fleet.submit(grid.x_of(p), grid.y_of(p), grid.x_of(d), grid.y_of(d), 0).accepted) ++open;
    }
    fleet.advance();
    const auto t0 = std::chrono::steady_clock::now();
    const DispatchStats st = disp.dispatch(fleet, dist, {});
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    res.dispatch_s += dt;
    res.dispatch_max_s = std::max(res.dispatch_max_s, dt);
    res.empty_travel += st.travel;
    res.assignments += st.assigned + st.reassigned;
    res.reassigned += st.reassigned;
    fleet.take_events();
    fleet.fill_positions(pos);
    fleet.fill_goals(goals);
    gdrhcr::WorldView world{grid, dist, t, pos, goals};
    next = pos;
    planner->plan_step(world, next);
    if (auto v = validator.check(pos, next)) {
      std::fprintf(stderr, "collision at step %d: %s\n", t, v->describe(grid, t).c_str());
      std::exit(3);
    }
    for (int r = 0; r < robots; ++r) fleet.update_robot(r, grid.x_of(next[r]), grid.y_of(next[r]), false, false, err);
  }
  fleet.advance();
  res.delivered = fleet.delivered_total();
  return res;
}

}  // namespace

int main(int argc, char** argv) {
  std::string map_path = "maps/warehouse-10-20-10-2-1.map", planner = "pibt";
  int robots = 200, steps = 1200, seeds = 3;
  double tick_rate = 2.0;
  try {
    const BenchOptions cl(argc, argv, {"map", "robots", "steps", "seeds", "planner", "tick-rate"});
    if (cl.help()) {
      std::printf("dispatch_benchmark --map PATH (%s) --robots N (%d) --steps N (%d) --seeds N (%d) --planner NAME (%s) "
                  "--tick-rate HZ (%g)\n", map_path.c_str(), robots, steps, seeds, planner.c_str(), tick_rate);
      return 0;
    }
    map_path = cl.text("map", map_path);
    planner = cl.text("planner", planner);
    robots = static_cast<int>(cl.integer("robots", robots, 1, 1000000));
    steps = static_cast<int>(cl.integer("steps", steps, 1, 10000000));
    seeds = static_cast<int>(cl.integer("seeds", seeds, 1, 1000000));
    tick_rate = cl.real("tick-rate", tick_rate, 1e-3, 1000);
  } catch (const BenchOptionError& e) {
    std::fprintf(stderr, "dispatch_benchmark: %s\n", e.what());
    return 2;
  }
  const LoadedMap map = load_map(map_path, 1.0);
  const auto mapd = map.format == "map_server" ? gdrhcr::default_mapd_cells(map.grid)
                                               : gdrhcr::mapd_cells_for_map(map.grid, map_path);
  std::printf("map %s, %d robots, planner %s, %d steps at %.1f Hz (%.0f s), full load (2 x robots open)\n",
              map_path.c_str(), robots, planner.c_str(), steps, tick_rate, steps / tick_rate);
  std::printf("%-7s %5s %10s %14s %16s %12s %14s %14s\n", "policy", "seed", "delivered", "deliveries/h",
              "cells to pickup", "reassigned", "dispatch ms", "dispatch max ms");
  double sum[2] = {0, 0};
  for (int s = 1; s <= seeds; ++s) {
    int k = 0;
    for (DispatchPolicy p : {DispatchPolicy::kGreedy, DispatchPolicy::kBatch}) {
      const Result r = run(map, mapd, p, planner, robots, steps, s);
      const double per_hour = r.delivered * 3600.0 * tick_rate / steps;
      sum[k++] += per_hour;
      std::printf("%-7s %5d %10llu %14.0f %16.2f %12llu %14.3f %14.3f\n", dispatch_policy_name(p), s,
                  (unsigned long long)r.delivered, per_hour, r.assignments ? r.empty_travel / r.assignments : 0.0,
                  (unsigned long long)r.reassigned, 1e3 * r.dispatch_s / steps, 1e3 * r.dispatch_max_s);
      std::fflush(stdout);
    }
  }
  std::printf("mean deliveries/h: greedy %.0f, batch %.0f (%+.1f%%)\n", sum[0] / seeds, sum[1] / seeds,
              100.0 * (sum[1] - sum[0]) / sum[0]);
  return 0;
}
