// Benchmark (not a test): PIBT time per step on warehouse-10-20-10-2-1.
//   bench_pibt [--map FILE] [--agents N] [--steps N] [--seed N] [--tasks random|mapd]
// Target from the foundation issue: well under 5 ms per step for 1000 agents on one core.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "gdrhcr/guided_pibt.hpp"
#include "gdrhcr/simulator.hpp"

using namespace gdrhcr;

namespace {
// Wraps a planner to record the wall time of each step.
class TimedPlanner : public Planner {
 public:
  explicit TimedPlanner(Planner& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name(); }
  nlohmann::json params() const override { return inner_.params(); }
  StepReport plan_step(const WorldView& w, std::vector<Cell>& next) override {
    auto t0 = std::chrono::steady_clock::now();
    auto r = inner_.plan_step(w, next);
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    return r;
  }
  std::vector<double> times;

 private:
  Planner& inner_;
};
}  // namespace

int main(int argc, char** argv) {
  std::string map = std::string(GDRHCR_MAPS_DIR) + "/warehouse-10-20-10-2-1.map";
  std::string tasks_kind = "random";
  int agents = 1000, steps = 500;
  uint64_t seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--map")) map = argv[i + 1];
    else if (!std::strcmp(argv[i], "--agents")) agents = std::stoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--steps")) steps = std::stoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--seed")) seed = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--tasks")) tasks_kind = argv[i + 1];
    else { std::fprintf(stderr, "unknown option %s\n", argv[i]); return 2; }
  }
  Grid grid = Grid::load(map);
  DistTable dist(grid);
  std::unique_ptr<TaskStream> tasks;
  if (tasks_kind == "mapd") {
    auto cells = default_mapd_cells(grid);
    tasks = std::make_unique<PickupDeliveryStream>(grid, cells.pickups, cells.deliveries, seed);
  } else {
    tasks = std::make_unique<RandomNavigationStream>(grid, seed);
  }
  PibtPlanner pibt(grid, agents, seed);
  TimedPlanner timed(pibt);
  SimOptions opt;
  opt.steps = steps;
  SimResult r = run_simulation(grid, dist, *tasks, timed, random_starts(grid, agents, seed), opt);
  auto t = timed.times;
  std::sort(t.begin(), t.end());
  double sum = 0;
  for (double x : t) sum += x;
  auto pct = [&](double p) { return t[std::min(t.size() - 1, size_t(p * t.size()))] * 1e3; };
  std::printf("bench_pibt map=%s tasks=%s agents=%d steps=%d seed=%llu\n", map.c_str(),
              tasks_kind.c_str(), agents, steps, (unsigned long long)seed);
  std::printf("  ms per step: mean %.3f  p50 %.3f  p99 %.3f  max %.3f  (target < 5 ms)\n",
              sum / t.size() * 1e3, pct(0.5), pct(0.99), t.back() * 1e3);
  std::printf("  throughput %.3f (free flow %.3f, ratio %.2f), collisions 0, distance rows %zu (%.1f MB)\n",
              r.throughput, r.free_flow_throughput, r.throughput / r.free_flow_throughput,
              dist.cached_rows(), dist.cached_bytes() / 1e6);
  return 0;
}
