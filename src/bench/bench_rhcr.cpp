// Benchmark (not a test): RHCR (PBS + SIPP, PIBT fallback) time per PBS call and throughput on
// warehouse-10-20-10-2-1 and kiva.map, random goals on every free cell, H = 20, alpha = 5,
// next to the figures of the reference implementation (Jiaoyang-Li/RHCR, Li et al. AAAI 2021)
// measured on a comparable machine. Agent counts rise per map until PBS calls time out.
//   bench_rhcr [--steps 500] [--timeout 60] [--seed 1] [--maps warehouse,kiva]
//              [--warehouse-agents 100,200,400] [--kiva-agents 100,150,200]
#include <time.h>

#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>
#include <string>

#include "gdrhcr/rhcr.hpp"
#include "gdrhcr/simulator.hpp"

using namespace gdrhcr;

namespace {
double thread_cpu_s() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

// Records the CPU time of the steps in which PBS ran.
class CpuTimedPlanner : public Planner {
 public:
  explicit CpuTimedPlanner(Planner& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name(); }
  nlohmann::json params() const override { return inner_.params(); }
  nlohmann::json stats() const override { return inner_.stats(); }
  StepReport plan_step(const WorldView& w, std::vector<Cell>& next) override {
    const double c0 = thread_cpu_s();
    StepReport r = inner_.plan_step(w, next);
    if (r.planned) {
      const double c = thread_cpu_s() - c0;
      cpu_sum += c, cpu_max = std::max(cpu_max, c), ++calls;
    }
    return r;
  }
  double cpu_sum = 0, cpu_max = 0;
  long calls = 0;

 private:
  Planner& inner_;
};

struct Reference {
  double pbs_s, throughput;
};
// Jiaoyang-Li/RHCR (PBS, H = 20, alpha = 5, 500 steps), CPU seconds per PBS call.
const std::map<std::pair<std::string, int>, Reference> kReference = {
    {{"warehouse", 100}, {0.016, 1.17}}, {{"warehouse", 200}, {0.069, 2.23}},
    {{"warehouse", 400}, {0.61, 4.34}},  {{"kiva", 100}, {0.34, 3.53}},
    {{"kiva", 150}, {1.5, 4.59}},
};

std::vector<int> parse_list(const std::string& s) {
  std::vector<int> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(std::stoi(item));
  return out;
}
}  // namespace

int main(int argc, char** argv) {
  int steps = 500;
  double timeout = 60;
  uint64_t seed = 1;
  std::string maps = "warehouse,kiva";
  std::string warehouse_agents = "100,200,400", kiva_agents = "100,150,200";
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--steps")) steps = std::stoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--timeout")) timeout = std::stod(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--seed")) seed = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--maps")) maps = argv[i + 1];
    else if (!std::strcmp(argv[i], "--warehouse-agents")) warehouse_agents = argv[i + 1];
    else if (!std::strcmp(argv[i], "--kiva-agents")) kiva_agents = argv[i + 1];
    else { std::fprintf(stderr, "unknown option %s\n", argv[i]); return 2; }
  }
  std::printf("bench_rhcr: RHCR (PBS+SIPP, PIBT fallback), H=20 alpha=5, random goals on every free "
              "cell, %d steps, PBS timeout %.1f s, seed %llu\n",
              steps, timeout, (unsigned long long)seed);
  std::printf("%-10s %6s | %10s %10s %10s | %7s %7s | %5s %5s %5s | %10s %7s\n", "map", "agents",
              "cpu/call", "wall/call", "max/call", "thru", "free", "calls", "fail", "tmo",
              "ref s/call", "ref thr");
  for (const std::string& map : {std::string("warehouse"), std::string("kiva")}) {
    if (maps.find(map) == std::string::npos) continue;
    const std::string file = std::string(GDRHCR_MAPS_DIR) +
                             (map == "kiva" ? "/kiva.map" : "/warehouse-10-20-10-2-1.map");
    const Grid grid = Grid::load(file);
    for (int agents : parse_list(map == "kiva" ? kiva_agents : warehouse_agents)) {
      DistTable dist(grid);
      RandomNavigationStream tasks(grid, seed);
      RhcrConfig cfg;
      cfg.timeout_s = timeout;
      RhcrPlanner rhcr(grid, agents, seed, cfg);
      CpuTimedPlanner timed(rhcr);
      SimOptions opt;
      opt.steps = steps;
      const SimResult r = run_simulation(grid, dist, tasks, timed, random_starts(grid, agents, seed), opt);
      const auto s = rhcr.stats();
      const long timeouts = s["solver_timeouts"].get<long>();
      auto ref = kReference.find({map, agents});
      char refs[64] = "         -       -";
      if (ref != kReference.end())
        std::snprintf(refs, sizeof refs, "%10.3f %7.2f", ref->second.pbs_s, ref->second.throughput);
      std::printf("%-10s %6d | %10.4f %10.4f %10.4f | %7.3f %7.3f | %5ld %5ld %5ld | %s\n",
                  map.c_str(), agents, timed.calls ? timed.cpu_sum / timed.calls : 0.0,
                  r.plan_time_mean_s, r.plan_time_max_s, r.throughput, r.free_flow_throughput,
                  s["solver_calls"].get<long>(), s["solver_failures"].get<long>(), timeouts, refs);
      std::fflush(stdout);
      if (timeouts > 0) break;  // calls time out: larger counts only get worse
    }
  }
  return 0;
}
