// Delay-robust execution without ROS (issue 13): the planner node's execution layer (Executor,
// the Action Dependency Graph) and a core planner drive simulated robots (delayed_fleet.hpp: no safety
// interlock, LoRR-2026 random delays) with random goals; once without delays and once with
// p_delay per robot and tick, delays of 1..D ticks. Prints goals reached per tick, the ratio with
// delays to without, and robots delayed and waiting per tick; any collision, bad command or
// broken ADG invariant aborts the run. A benchmark (prints figures), not a test; seconds per run,
// so ideas can be tried here before the ROS benchmark (scripts/bench_delays.sh).
//   delay_benchmark --map maps/warehouse-10-20-10-2-1.map --robots 300 --ticks 300 --p-delay 0.01
//       --max-delay 20 --planner gd-rhcr --speed 6 --seeds 1 --commit-horizon 2
//       --between 1 [--param key=value ...]   (planner parameters, e.g. --param guidance=none)
// --between 1 (default): moves are dispatched the moment the robots ahead have left (the node's
// dispatch timer, Executor::advance after every substep); 0: at ticks only. --revoke 1 (default):
// moves queued behind late robots are taken back and planned again (ExecutorConfig); 0: kept.
// Each robot's goals come from its own random stream, so both runs of a seed give every robot
// the same goal sequence. DELAY_BENCH_STATS=1 prints the planner's counters after each run.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "delayed_fleet.hpp"
#include "gd_rhcr_planner/execution.hpp"
#include "gd_rhcr_planner/map_loader.hpp"
#include "gdrhcr/params.hpp"
#include "gdrhcr/planner.hpp"

using namespace gd_rhcr_planner;

namespace {

struct Options {
  std::string map = "maps/warehouse-10-20-10-2-1.map", planner = "gd-rhcr";
  int robots = 300, ticks = 300, max_delay = 20, speed = 6, seeds = 1, commit_horizon = 2, between = 1, revoke = 1;  // the node's defaults
  double p_delay = 0.01;
  std::vector<std::pair<std::string, std::string>> params;  // --param key=value, for the planner
};

struct Result {
  int goals = 0;
  double delayed = 0, waiting = 0, held = 0, moves = 0;  // per tick
  long revoked = 0;
  std::string error;
};

Result run(const gdrhcr::Grid& g, const Options& o, double p_delay, uint64_t seed) {
  gdrhcr::DistTable dist(g);
  gdrhcr::Params params, none;
  // Node-budget mode: the same plans on any machine (no timeouts).
  if (o.planner == "gd-rhcr") params.set("timeout", "1e6"), params.set("node-budget", "2000");
  for (const auto& [k, v] : o.params) params.set(k, v);
  auto primary = gdrhcr::make_planner(o.planner, params, g, o.robots, seed);
  params.check_all_used(o.planner);  // a misspelt --param is an error, not ignored
  DeadlinePlanner planner(std::move(primary), gdrhcr::make_planner("pibt", none, g, o.robots, seed));
  ExecutorConfig cfg;
  cfg.commit_horizon = o.commit_horizon;
  cfg.revoke_behind_late = o.revoke != 0;
  Executor ex(g, dist, o.robots, cfg);
  DelayedFleet fleet(g, o.robots, seed, o.speed, o.speed);
  Result r;
  for (int t = 0; t < o.ticks; ++t) {
    auto goals = fleet.goals(r.goals);
    const TickOutput out = ex.tick(fleet.records(), goals, planner, true);
    if (!out.stepped) r.error = "no step: " + out.skip_reason;
    else if (!out.plan_error.empty()) r.error = "plan rejected: " + out.plan_error;
    else r.error = ex.check_invariants();
    if (r.error.empty())
      r.error = fleet.execute(out, p_delay, o.max_delay, o.between ? DelayedFleet::on_arrival(ex) : nullptr);
    if (!r.error.empty()) {
      r.error = "tick " + std::to_string(t) + ": " + r.error;
      return r;
    }
    r.delayed += fleet.delayed();
    r.waiting += out.waiting;
    r.held += out.held;
    r.revoked += out.revoked;
  }
  for (const SimRobot& s : fleet.robots()) r.moves += s.moves;
  planner.wait_idle();
  if (std::getenv("DELAY_BENCH_STATS"))
    std::fprintf(stderr, "p %.3f: revoked %ld; %s\n", p_delay, r.revoked, planner.primary().stats().dump().c_str());
  r.delayed /= o.ticks;
  r.waiting /= o.ticks;
  r.held /= o.ticks;
  r.moves /= o.ticks;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--map") o.map = v;
    else if (k == "--planner") o.planner = v;
    else if (k == "--robots") o.robots = std::atoi(v.c_str());
    else if (k == "--ticks") o.ticks = std::atoi(v.c_str());
    else if (k == "--max-delay") o.max_delay = std::atoi(v.c_str());
    else if (k == "--speed") o.speed = std::atoi(v.c_str());
    else if (k == "--seeds") o.seeds = std::atoi(v.c_str());
    else if (k == "--commit-horizon") o.commit_horizon = std::atoi(v.c_str());
    else if (k == "--between") o.between = std::atoi(v.c_str());
    else if (k == "--revoke") o.revoke = std::atoi(v.c_str());
    else if (k == "--param" && v.find('=') != std::string::npos)
      o.params.emplace_back(v.substr(0, v.find('=')), v.substr(v.find('=') + 1));
    else if (k == "--p-delay") o.p_delay = std::atof(v.c_str());
    else {
      std::fprintf(stderr,
                   "unknown option %s (--map --planner --robots --ticks --p-delay --max-delay --speed "
                   "--seeds --commit-horizon --between 0|1 --revoke 0|1 --param key=value)\n",
                   k.c_str());
      return 2;
    }
  }
  if (o.robots < 1 || o.ticks < 1 || o.seeds < 1 || o.max_delay < 1 || o.commit_horizon < 1 || o.speed < 1 || o.speed > SimRobot::kSub ||
      !(o.p_delay >= 0 && o.p_delay <= 1)) {
    std::fprintf(stderr, "--robots, --ticks, --seeds, --max-delay, --commit-horizon must be >= 1, --speed in 1..%d (substeps of a "
                 "tick per move), --p-delay in [0, 1]\n", SimRobot::kSub);
    return 2;
  }
  try {
    const LoadedMap map = load_map(o.map, 1.0);
    std::printf("map %s, %d robots, planner %s, ADG execution (commit horizon %d, dispatch %s), %d ticks, moves take %.1f tick, "
                "delays p %.3f per tick of 1..%d ticks, random goals\n",
                o.map.c_str(), o.robots, o.planner.c_str(), o.commit_horizon,
                o.between ? "on arrival" : "at ticks", o.ticks,
                o.speed / double(SimRobot::kSub), o.p_delay, o.max_delay);
    std::printf("%5s %14s %14s %7s %16s %16s %12s %14s\n", "seed", "goals/tick no", "goals/tick p", "ratio",
                "delayed robots", "waiting no / p", "held moves", "moves no / p");
    double sum_ratio = 0;
    for (int s = 1; s <= o.seeds; ++s) {
      const Result a = run(map.grid, o, 0.0, s), b = run(map.grid, o, o.p_delay, s);
      for (const Result* r : {&a, &b})
        if (!r->error.empty()) {
          std::printf("seed %d: %s\n", s, r->error.c_str());
          return 1;
        }
      const double ta = double(a.goals) / o.ticks, tb = double(b.goals) / o.ticks;
      sum_ratio += tb / ta;
      std::printf("%5d %14.3f %14.3f %6.1f%% %16.1f %7.1f / %6.1f %5.1f / %4.1f %6.0f / %5.0f\n", s, ta, tb, 100 * tb / ta,
                  b.delayed, a.waiting, b.waiting, a.held, b.held, a.moves, b.moves);
      std::fflush(stdout);
    }
    std::printf("mean ratio %.1f%%\n", 100 * sum_ratio / o.seeds);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "delay_benchmark: %s\n", e.what());
    return 2;
  }
  return 0;
}
