// Benchmark (not a test): one large lifelong run, for fleets of thousands of agents (issue 12).
//   bench_scale --map FILE --planner NAME --agents N [--steps 300] [--seed 1] [--lookahead 3]
//               [--dist-budget-mb 256] [--json FILE] [planner options, e.g. --threads 2]
// Random goals. Prints one line: ms per step (mean, p50, p99, max, the wall time of plan_step
// around the planner; and the mean process CPU time of a step, all threads, which a busy
// machine disturbs less), peak RSS of this process, throughput, distance-table BFS runs during the
// steps (the free-flow bound computed afterwards is not counted) and bytes.
// --json appends the same figures as one JSON line (scripts/bench_scale.sh collects them).
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>

#include "gdrhcr/planner.hpp"
#include "gdrhcr/simulator.hpp"

using namespace gdrhcr;

namespace {
class TimedPlanner : public Planner {
 public:
  explicit TimedPlanner(Planner& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name(); }
  nlohmann::json params() const override { return inner_.params(); }
  nlohmann::json stats() const override { return inner_.stats(); }
  StepReport plan_step(const WorldView& w, std::vector<Cell>& next) override {
    const auto t0 = std::chrono::steady_clock::now();
    // From one plan_step to the next: the planner plus the simulator's work between steps
    // (validation, new goals, and the BFS of every new current goal, which the simulator asks
    // for to judge lateness, so the planner later finds those rows cached).
    if (w.timestep > 0) loop.push_back(std::chrono::duration<double>(t0 - last_start).count());
    last_start = t0;
    auto r = inner_.plan_step(w, next);
    times.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    bfs_in_steps = w.dist.bfs_count();  // the free-flow bound computed after the run adds more
    return r;
  }
  std::vector<double> times, loop;
  std::chrono::steady_clock::time_point last_start;
  uint64_t bfs_in_steps = 0;

 private:
  Planner& inner_;
};

long peak_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;  // kilobytes on Linux
}
}  // namespace

int main(int argc, char** argv) {
  Params args;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a.rfind("--", 0) != 0 || i + 1 >= argc) {
      std::fprintf(stderr, "bench_scale: expected --option value pairs, got '%s'\n", a.c_str());
      return 2;
    }
    args.set(a.substr(2), argv[++i]);
  }
  try {
    const std::string map = args.get_string("map", std::string(GDRHCR_MAPS_DIR) + "/warehouse-20-40-10-2-2.map");
    const std::string planner_name = args.get_string("planner", "pibt");
    const int agents = args.get_int("agents", 2000, 1, 10000000);
    const int steps = args.get_int("steps", 300, 1, 100000000);
    const uint64_t seed = args.get_u64("seed", 1);
    const int lookahead = args.get_int("lookahead", 3, 1, 1000);
    const int budget_mb = args.get_int("dist-budget-mb", 256, 1, 1 << 20);
    const std::string json_path = args.get_string("json", "");
    const Grid grid = Grid::load(map);
    DistTable dist(grid, size_t(budget_mb) << 20);
    RandomNavigationStream tasks(grid, seed);
    auto planner = make_planner(planner_name, args, grid, agents, seed);
    args.check_all_used("bench_scale --planner " + planner_name);
    TimedPlanner timed(*planner);
    SimOptions opt;
    opt.steps = steps;
    opt.lookahead = lookahead;
    const SimResult r = run_simulation(grid, dist, tasks, timed, random_starts(grid, agents, seed), opt);

    auto t = timed.times;
    std::sort(t.begin(), t.end());
    double sum = 0;
    for (double x : t) sum += x;
    auto pct = [&](double p) { return t[std::min(t.size() - 1, size_t(p * t.size()))] * 1e3; };
    const double mean_ms = sum / t.size() * 1e3;
    auto loop = timed.loop;
    std::sort(loop.begin(), loop.end());
    double loop_sum = 0;
    for (double x : loop) loop_sum += x;
    const double loop_mean_ms = loop.empty() ? 0 : loop_sum / loop.size() * 1e3;
    const double loop_p99_ms = loop.empty() ? 0 : loop[std::min(loop.size() - 1, size_t(0.99 * loop.size()))] * 1e3;
    const long rss = peak_rss_kb();
    std::printf("bench_scale map=%s planner=%s agents=%d steps=%d seed=%llu\n", map.c_str(), planner->name().c_str(),
                agents, steps, (unsigned long long)seed);
    std::printf("  ms per step: mean %.2f  p50 %.2f  p99 %.2f  max %.2f (CPU, all threads: mean %.2f; step to "
                "step with the simulator's BFS: mean %.2f p99 %.2f) | peak RSS %.0f MB | throughput %.3f "
                "(free flow %.3f) | BFS %llu, rows cached %zu, %.0f MB (peak %.0f MB, budget %d MB, over-budget "
                "inserts %llu) | wall %.1f s\n",
                mean_ms, pct(0.5), pct(0.99), t.back() * 1e3, r.step_cpu_mean_s * 1e3, loop_mean_ms, loop_p99_ms, rss / 1024.0, r.throughput, r.free_flow_throughput,
                (unsigned long long)timed.bfs_in_steps, dist.cached_rows(), dist.cached_bytes() / 1048576.0,
                dist.peak_bytes() / 1048576.0, budget_mb, (unsigned long long)dist.over_budget_inserts(), r.wall_time_s);
    if (!json_path.empty()) {
      nlohmann::json j = {{"map", map}, {"planner", planner->name()}, {"agents", agents}, {"steps", steps},
                          {"seed", seed}, {"lookahead", lookahead}, {"params", planner->params()},
                          {"ms_per_step_mean", mean_ms}, {"ms_per_step_p50", pct(0.5)},
                          {"ms_per_step_p99", pct(0.99)}, {"ms_per_step_max", t.back() * 1e3},
                          {"cpu_ms_per_step_mean", r.step_cpu_mean_s * 1e3},
                          {"loop_ms_per_step_mean", loop_mean_ms}, {"loop_ms_per_step_p99", loop_p99_ms},
                          {"plan_time_mean_s", r.plan_time_mean_s}, {"peak_rss_mb", rss / 1024.0},
                          {"throughput", r.throughput}, {"free_flow_throughput", r.free_flow_throughput},
                          {"goals_reached", r.goals_reached}, {"collisions", r.collisions},
                          {"bfs_runs", timed.bfs_in_steps}, {"bfs_runs_with_free_flow", dist.bfs_count()}, {"dist_bytes_peak", dist.peak_bytes()},
                          {"dist_rows_cached", dist.cached_rows()}, {"dist_bytes_per_row", dist.row_bytes()},
                          {"dist_over_budget_inserts", dist.over_budget_inserts()}, {"wall_time_s", r.wall_time_s},
                          {"stats", planner->stats()}};
      std::ofstream(json_path, std::ios::app) << j.dump() << "\n";
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_scale: error: %s\n", e.what());
    return 2;
  }
}
