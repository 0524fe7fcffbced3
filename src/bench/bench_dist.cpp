// Benchmark (not a test): distance-table rows per second and bytes per row, against a plain BFS
// into an int32 array over all grid cells (what DistRow was before issue 12) in the same binary.
//   bench_dist [--map FILE] [--goals N] [--seed N] [--reps N]
// Prints, per method: rows per second (best of --reps runs over the same N distinct goals),
// bytes per row, and a checksum of all distances so the methods can be seen to agree.
//   plain        int32 per grid cell, std::vector queue, grid neighbour lists (the baseline)
//   row()        DistTable::row one goal at a time (compact rows, one thread)
//   prefetch(T)  DistTable::prefetch of the whole batch on a oneTBB arena of T threads
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include <tbb/task_arena.h>

#include "gdrhcr/dist_table.hpp"

using namespace gdrhcr;
using Clock = std::chrono::steady_clock;

namespace {
std::vector<int32_t> plain_bfs(const Grid& grid, Cell goal, std::vector<Cell>& queue) {
  std::vector<int32_t> d(grid.num_cells(), kUnreachable);
  queue.clear();
  d[goal] = 0;
  queue.push_back(goal);
  for (size_t head = 0; head < queue.size(); ++head) {
    const Cell c = queue[head];
    for (Cell n : grid.neighbours(c)) {
      if (d[n] != kUnreachable) continue;
      d[n] = d[c] + 1;
      queue.push_back(n);
    }
  }
  return d;
}

// Sum of distances from a fixed sample of free cells, to compare methods.
template <typename Lookup>
long long checksum(const Grid& grid, const std::vector<Cell>& goals, Lookup&& at) {
  long long s = 0;
  for (size_t k = 0; k < goals.size(); ++k)
    for (size_t i = k % 13; i < grid.free_cells().size(); i += 97) s += at(k, grid.free_cells()[i]);
  return s;
}

double seconds(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace

int main(int argc, char** argv) {
  std::string map = std::string(GDRHCR_MAPS_DIR) + "/warehouse-20-40-10-2-2.map";
  int n = 2000, reps = 3;
  uint64_t seed = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--map")) map = argv[i + 1];
    else if (!std::strcmp(argv[i], "--goals")) n = std::stoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--seed")) seed = std::stoull(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--reps")) reps = std::stoi(argv[i + 1]);
    else { std::fprintf(stderr, "unknown option %s\n", argv[i]); return 2; }
  }
  const Grid grid = Grid::load(map);
  std::vector<Cell> goals = grid.free_cells();
  std::shuffle(goals.begin(), goals.end(), std::mt19937_64(seed));
  goals.resize(std::min<size_t>(n, goals.size()));
  n = static_cast<int>(goals.size());
  std::printf("bench_dist map=%s (%d x %d, %zu free cells) goals=%d reps=%d\n", map.c_str(), grid.width(),
              grid.height(), grid.free_cells().size(), n, reps);

  // Baseline: plain BFS, one goal at a time; the rows are kept, as a cache would.
  double best = 1e30;
  long long sum_plain = 0;
  size_t plain_bytes = 0;
  for (int r = 0; r < reps; ++r) {
    std::vector<std::vector<int32_t>> rows;
    rows.reserve(n);
    std::vector<Cell> queue;
    queue.reserve(grid.free_cells().size());
    const auto t0 = Clock::now();
    for (Cell g : goals) rows.push_back(plain_bfs(grid, g, queue));
    best = std::min(best, seconds(t0));
    sum_plain = checksum(grid, goals, [&](size_t k, Cell c) { return rows[k][c]; });
    plain_bytes = rows[0].capacity() * sizeof(int32_t);
  }
  std::printf("  %-13s %10.0f rows/s  %9zu bytes/row  checksum %lld\n", "plain", n / best, plain_bytes, sum_plain);

  auto run_table = [&](const char* label, int threads) {
    double best_t = 1e30;
    long long sum = 0;
    size_t bytes = 0, index_bytes = 0;
    for (int r = 0; r < reps; ++r) {
      DistTable table(grid, size_t(1) << 40);
      const auto t0 = Clock::now();
      if (threads == 0) {
        for (Cell g : goals) table.row(g);
      } else {
        tbb::task_arena arena(threads);
        arena.execute([&] { table.prefetch(goals); });
      }
      best_t = std::min(best_t, seconds(t0));
      if (table.bfs_count() != goals.size()) {
        std::fprintf(stderr, "bench_dist: %s ran %llu BFS for %d goals\n", label,
                     (unsigned long long)table.bfs_count(), n);
        std::exit(1);
      }
      std::vector<std::shared_ptr<const DistRow>> rows;
      for (Cell g : goals) rows.push_back(table.row(g));
      sum = checksum(grid, goals, [&](size_t k, Cell c) { return (*rows[k])[c]; });
      bytes = table.cached_bytes() / goals.size();
      index_bytes = table.index_bytes();
    }
    std::printf("  %-13s %10.0f rows/s  %9zu bytes/row  checksum %lld%s  (x%.2f plain; shared index %zu bytes)\n",
                label, n / best_t, bytes, sum, sum == sum_plain ? "" : " MISMATCH", best / best_t, index_bytes);
    return sum == sum_plain;
  };
  bool ok = run_table("row()", 0);
  ok = run_table("prefetch(1)", 1) && ok;
  ok = run_table("prefetch(2)", 2) && ok;
  return ok ? 0 : 1;
}
