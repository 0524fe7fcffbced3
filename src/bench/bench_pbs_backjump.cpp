// Benchmark (not a test): PBS with and without backjumping (pbs.hpp) on identical instances.
// Backjumping is our addition to PBS and its argument in pbs.hpp does not cover failures found
// below the node it jumps over, so this A/B decides whether it stays on: the same windowed
// instances (random starts, each agent's next three random goals, H = 20) are solved with both
// settings under the same deterministic node budget, and the figures printed are the solved
// count, the instances only one setting solves, PBS nodes and CPU time.
//   bench_pbs_backjump [--instances 30] [--budget 3000] [--seed 1]
#include <time.h>

#include <cstdio>
#include <cstring>
#include <string>

#include "gdrhcr/pbs.hpp"
#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {
double cpu_s() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec + ts.tv_nsec * 1e-9;
}

struct Tally {
  int solved = 0, only = 0;
  long nodes = 0;
  double cpu = 0;
};
}  // namespace

int main(int argc, char** argv) {
  int instances = 30;
  long budget = 3000;
  uint64_t seed0 = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--instances")) instances = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--budget")) budget = std::atol(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--seed")) seed0 = std::strtoull(argv[i + 1], nullptr, 10);
    else { std::fprintf(stderr, "bench_pbs_backjump: unknown option %s\n", argv[i]); return 2; }
  }
  const std::string maps = GDRHCR_MAPS_DIR;
  struct Setting { const char* map; int agents; };
  // From easy to where PBS starts to fail (dead ends are where backjumping acts).
  const Setting settings[] = {{"warehouse-10-20-10-2-1", 300}, {"warehouse-10-20-10-2-1", 500},
                              {"warehouse-10-20-10-2-1", 700}, {"random-32-32-20", 100},
                              {"random-32-32-20", 150}, {"random-32-32-20", 200},
                              {"empty-48-48", 400}, {"empty-48-48", 600}};
  std::printf("# PBS backjumping A/B: %d identical instances per row, node budget %ld, H = 20\n\n", instances, budget);
  std::printf("| map | agents | solved with | solved without | only with | only without | nodes with | nodes without | cpu s with | cpu s without |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& s : settings) {
    Grid g = Grid::load(maps + "/" + s.map + ".map");
    DistTable dist(g);
    Tally on, off;
    for (int k = 0; k < instances; ++k) {
      const uint64_t seed = seed0 * 1000 + k;
      const auto starts = random_starts(g, s.agents, seed);
      RandomNavigationStream tasks(g, seed);
      std::vector<std::vector<Cell>> goals(s.agents);
      for (int a = 0; a < s.agents; ++a) {
        Cell last = starts[a];
        for (int j = 0; j < 3; ++j) goals[a].push_back(last = tasks.next_goal(a, last));
      }
      bool ok[2];
      for (int variant = 0; variant < 2; ++variant) {
        PbsConfig pc;
        pc.horizon = 20;
        pc.time_limit_s = 1e6;
        pc.node_budget = budget;
        pc.backjump = variant == 0;
        const double c0 = cpu_s();
        const PbsResult r = solve_pbs(g, dist, starts, goals, nullptr, pc);
        Tally& t = variant == 0 ? on : off;
        t.cpu += cpu_s() - c0;
        t.nodes += r.nodes;
        t.solved += r.success;
        ok[variant] = r.success;
        if (r.success && first_collision(g, r.paths, pc.horizon).t >= 0) {
          std::fprintf(stderr, "bench_pbs_backjump: a returned plan collides (%s, %d agents, seed %llu)\n",
                       s.map, s.agents, static_cast<unsigned long long>(seed));
          return 3;
        }
      }
      on.only += ok[0] && !ok[1];
      off.only += ok[1] && !ok[0];
    }
    std::printf("| %s | %d | %d | %d | %d | %d | %.0f | %.0f | %.3f | %.3f |\n", s.map, s.agents, on.solved,
                off.solved, on.only, off.only, double(on.nodes) / instances, double(off.nodes) / instances,
                on.cpu / instances, off.cpu / instances);
    std::fflush(stdout);
  }
  return 0;
}
