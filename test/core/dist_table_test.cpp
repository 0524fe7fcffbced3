// BFS distances against hand-checked cases, laziness, and the memory budget.
#include <gtest/gtest.h>

#include <thread>

#include "gdrhcr/dist_table.hpp"

using namespace gdrhcr;

TEST(DistTable, HandCheckedDistancesAroundAWall) {
  // The wall forces a detour: from (0,0) to (2,0) is 2 by Manhattan distance but 6 by path.
  Grid g = Grid::from_rows({
      ".@...",
      ".@.@.",
      ".....",
  });
  DistTable d(g);
  EXPECT_EQ(d.get(g.cell(2, 0), g.cell(0, 0)), 6);
  EXPECT_EQ(d.get(g.cell(0, 0), g.cell(2, 0)), 6);  // symmetric
  EXPECT_EQ(d.get(g.cell(2, 0), g.cell(2, 0)), 0);
  EXPECT_EQ(d.get(g.cell(4, 0), g.cell(0, 2)), 6);
  EXPECT_EQ(d.get(g.cell(2, 1), g.cell(4, 1)), 4);
  EXPECT_GE(d.get(g.cell(2, 0), g.cell(1, 0)), kUnreachable);  // obstacle
}

TEST(DistTable, UnreachableComponent) {
  Grid g = Grid::from_rows({"..@.."});
  DistTable d(g);
  EXPECT_EQ(d.get(g.cell(0, 0), g.cell(1, 0)), 1);
  EXPECT_GE(d.get(g.cell(0, 0), g.cell(4, 0)), kUnreachable);
}

TEST(DistTable, BlockedGoalIsAnError) {
  Grid g = Grid::from_rows({".@."});
  DistTable d(g);
  EXPECT_THROW(d.row(g.cell(1, 0)), std::out_of_range);
  EXPECT_THROW(d.row(-1), std::out_of_range);
}

TEST(DistTable, LazyAndCached) {
  Grid g = Grid::from_rows({"....", "....", "...."});
  DistTable d(g);
  EXPECT_EQ(d.cached_rows(), 0u);
  d.get(g.cell(0, 0), g.cell(3, 2));
  d.get(g.cell(0, 0), g.cell(1, 2));
  EXPECT_EQ(d.bfs_count(), 1u);
  d.get(g.cell(1, 1), g.cell(0, 0));
  EXPECT_EQ(d.bfs_count(), 2u);
  EXPECT_EQ(d.cached_rows(), 2u);
}

TEST(DistTable, BudgetEvictsLeastRecentlyUsedRows) {
  Grid g = Grid::from_rows(std::vector<std::string>(20, std::string(20, '.')));
  const size_t row_bytes = 400 * sizeof(int32_t);
  DistTable d(g, 10 * row_bytes);
  auto held = d.row(g.cell(0, 0));  // a row kept by a solver survives eviction
  for (int i = 1; i < 100; ++i) d.get(g.cell(i % 20, i / 20), 0);
  EXPECT_LE(d.cached_bytes(), 10 * row_bytes);
  EXPECT_EQ((*held)[g.cell(3, 4)], 7);
  // Evicted rows are recomputed with the same answer.
  EXPECT_EQ(d.get(g.cell(1, 0), g.cell(19, 19)), 18 + 19);
}

TEST(DistTable, ConcurrentQueriesAgree) {
  Grid g = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/random-32-32-20.map");
  DistTable d(g, 64 * 1024);  // small budget: eviction races with lookups
  std::vector<std::thread> threads;
  std::vector<long> sums(4, 0);
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (size_t i = 0; i < g.free_cells().size(); i += 7)
        sums[t] += d.get(g.free_cells()[i], g.free_cells()[0]);
    });
  for (auto& th : threads) th.join();
  for (int t = 1; t < 4; ++t) EXPECT_EQ(sums[t], sums[0]);
  EXPECT_GT(sums[0], 0);
}
