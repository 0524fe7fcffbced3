// Benchmark (not a test): PIBT time per step on warehouse-10-20-10-2-1.
//   bench_pibt [--map FILE] [--agents N] [--steps N] [--seed N] [--tasks random|mapd]
// Target from the foundation issue: well under 5 ms per step for 1000 agents on one core.
//   bench_pibt --lorr-problem FILE [--steps N] [--seed N] [--dist-budget-mb 8192]
// A League of Robot Runners problem instead (its map, fleet and task list, the rotation model):
// PIBT with the product's parameters for that map and fleet, every free cell's distance row
// computed before the first step (as the Start-Kit adapter does), so the figure is PIBT's own
// step with its row reads, the part of warehouse_large's step that takes most of it.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <string>

#include "gdrhcr/guided_pibt.hpp"
#include "gdrhcr/lorr_io.hpp"
#include "gdrhcr/mapf_in_rotation.hpp"
#include "gdrhcr/planner_params.hpp"
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

// One line: ms per step, mean and percentiles, then `note`.
void print_times(std::vector<double> t, const char* note) {
  std::sort(t.begin(), t.end());
  double sum = 0;
  for (double x : t) sum += x;
  auto pct = [&](double p) { return t[std::min(t.size() - 1, size_t(p * t.size()))] * 1e3; };
  std::printf("  ms per step: mean %.3f  p50 %.3f  p99 %.3f  max %.3f%s\n", sum / t.size() * 1e3, pct(0.5), pct(0.99),
              t.back() * 1e3, note);
}

int run_lorr(const std::string& path, int steps, uint64_t seed, int budget_mb) {
  LorrProblem problem = load_lorr_problem(path);
  const Grid& grid = problem.grid;
  const int agents = problem.team_size;
  Params given;
  const PlannerParams values = PlannerParams::resolve("pibt", given, MapFacts(grid, agents, ActionModel::kRotation));
  DistTable dist(grid, ActionModel::kRotation, size_t(budget_mb) << 20, step_costs(values, ActionModel::kRotation));
  if (!dist.prefetch_all().fit) {
    std::fprintf(stderr, "bench_pibt: every free cell's row does not fit in --dist-budget-mb %d\n", budget_mb);
    return 2;
  }
  TaskListStream tasks(grid, problem.tasks, agents, problem.strategy);
  auto planner = make_planner_in(values, grid, agents, seed, ActionModel::kRotation, kLorrTurnPlanning);
  TimedPlanner timed(*planner);
  SimOptions opt;
  opt.steps = steps;
  opt.lookahead = problem.num_tasks_reveal;
  opt.action_model = ActionModel::kRotation;
  SimResult r = run_simulation(grid, dist, tasks, timed, problem.starts, opt);
  std::printf("bench_pibt lorr-problem=%s agents=%d steps=%d seed=%llu (rotation, every row computed first)\n",
              path.c_str(), agents, steps, (unsigned long long)seed);
  print_times(timed.times, "");
  std::printf("  goals %ld, collisions %ld\n", r.goals_reached, r.collisions);
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  std::string map = std::string(GDRHCR_MAPS_DIR) + "/warehouse-10-20-10-2-1.map";
  std::string tasks_kind = "random", lorr_path;
  int agents = 1000, steps = 500, budget_mb = 8192;
  uint64_t seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--map")) map = argv[i + 1];
    else if (!std::strcmp(argv[i], "--agents")) agents = std::stoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--steps")) steps = std::stoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--seed")) seed = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--tasks")) tasks_kind = argv[i + 1];
    else if (!std::strcmp(argv[i], "--lorr-problem")) lorr_path = argv[i + 1];
    else if (!std::strcmp(argv[i], "--dist-budget-mb")) budget_mb = std::stoi(argv[i + 1]);
    else { std::fprintf(stderr, "unknown option %s\n", argv[i]); return 2; }
  }
  if (!lorr_path.empty()) return run_lorr(lorr_path, steps, seed, budget_mb);
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
  std::printf("bench_pibt map=%s tasks=%s agents=%d steps=%d seed=%llu\n", map.c_str(),
              tasks_kind.c_str(), agents, steps, (unsigned long long)seed);
  print_times(timed.times, "  (target < 5 ms)");
  std::printf("  throughput %.3f (free flow %.3f, ratio %.2f), collisions 0, distance rows %zu (%.1f MB)\n",
              r.throughput, r.free_flow_throughput, r.throughput / r.free_flow_throughput,
              dist.cached_rows(), dist.cached_bytes() / 1e6);
  return 0;
}
