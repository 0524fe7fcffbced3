// BFS distances against hand-checked cases and a plain full BFS on random maps, compact rows
// (16-bit and 32-bit), laziness, the memory budget (counted bytes), batch prefetch and threads.
#include <gtest/gtest.h>

#include <deque>
#include <random>
#include <thread>

#include "gdrhcr/dist_table.hpp"

using namespace gdrhcr;

namespace {
// The reference: a plain BFS over grid cells into an int array (what DistRow used to be).
std::vector<int> plain_bfs(const Grid& g, Cell goal, const std::vector<uint8_t>& blocked = {}) {
  std::vector<int> d(g.num_cells(), kUnreachable);
  std::deque<Cell> q{goal};
  d[goal] = 0;
  while (!q.empty()) {
    Cell c = q.front();
    q.pop_front();
    for (Cell n : g.neighbours(c)) {
      if (d[n] != kUnreachable || (!blocked.empty() && blocked[n])) continue;
      d[n] = d[c] + 1;
      q.push_back(n);
    }
  }
  return d;
}

Grid random_map(int w, int h, double wall_density, std::mt19937_64& rng) {
  std::vector<std::string> rows(h, std::string(w, '.'));
  std::bernoulli_distribution wall(wall_density);
  for (auto& r : rows)
    for (auto& ch : r)
      if (wall(rng)) ch = '@';
  rows[0][0] = '.';  // at least one free cell
  return Grid::from_rows(rows);
}
}  // namespace

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
  EXPECT_THROW(d.rows({g.cell(0, 0), g.cell(1, 0)}), std::out_of_range);
  d.prefetch({g.cell(1, 0), -1, 99});  // skipped, no error
  EXPECT_EQ(d.bfs_count(), 0u);
}

TEST(DistTable, CompactRowsEqualAPlainBfsOnRandomMapsWithWalls) {
  // Many seeds, map sizes and wall densities (some maps split into several components), every
  // cell of every row, with and without blocked cells (offline robots).
  for (uint64_t seed = 1; seed <= 60; ++seed) {
    std::mt19937_64 rng(seed);
    const int w = 3 + int(rng() % 40), h = 1 + int(rng() % 30);
    const double density = 0.05 * double(rng() % 9);
    Grid g = random_map(w, h, density, rng);
    std::vector<Cell> blocked_cells;
    std::vector<uint8_t> blocked(g.num_cells(), 0);
    if (seed % 2 == 0)
      for (int k = 0; k < 3; ++k) {
        Cell c = g.free_cells()[rng() % g.free_cells().size()];
        blocked_cells.push_back(c);
        blocked[c] = 1;
      }
    DistTable d(g, blocked_cells);
    ASSERT_TRUE(d.row(g.free_cells()[0])->narrow());
    for (int k = 0; k < 8; ++k) {
      const Cell goal = g.free_cells()[rng() % g.free_cells().size()];
      const auto ref = plain_bfs(g, goal, blocked_cells.empty() ? std::vector<uint8_t>{} : blocked);
      const auto row = d.row(goal);
      for (Cell c = 0; c < g.num_cells(); ++c)
        ASSERT_EQ((*row)[c], ref[c]) << "seed " << seed << " goal " << g.describe(goal) << " cell " << g.describe(c);
    }
  }
}

TEST(DistTable, WideRowsPastSixtyFiveThousandFreeCells) {
  // A 300 x 480 serpentine (every other row a wall with one gap at alternating ends): 72,239
  // free cells, too many for 16-bit rows, so the 32-bit path is used; distances pass 65,535.
  std::vector<std::string> rows(480, std::string(300, '.'));
  for (int y = 1; y < 480; y += 2) {
    rows[y] = std::string(300, '@');
    rows[y][(y / 2) % 2 ? 0 : 299] = '.';
  }
  Grid g = Grid::from_rows(rows);
  ASSERT_GT(g.free_cells().size(), size_t(FreeCellIndex::kMaxNarrowFree));
  DistTable d(g);
  const Cell goal = g.cell(0, 0);
  const auto row = d.row(goal);
  EXPECT_FALSE(row->narrow());
  const auto ref = plain_bfs(g, goal);
  for (Cell c = 0; c < g.num_cells(); ++c) ASSERT_EQ((*row)[c], ref[c]) << g.describe(c);
  EXPECT_GT((*row)[g.cell(299, 478)], 65535);
  EXPECT_EQ(row->bytes(), sizeof(DistRow) + (g.free_cells().size() + 1) * 4);
}

TEST(DistTable, NarrowRowsAtTheLimit) {
  // A corridor of exactly 65,534 free cells: distances up to 65,533 still fit in 16 bits.
  const int n = FreeCellIndex::kMaxNarrowFree;
  Grid line = Grid::from_rows({std::string(n, '.')});
  DistTable d(line);
  auto row = d.row(line.cell(0, 0));
  EXPECT_TRUE(row->narrow());
  EXPECT_EQ((*row)[line.cell(n - 1, 0)], n - 1);
  EXPECT_EQ((*row)[line.cell(n / 2, 0)], n / 2);
}

// Every free cell's row before any goal is known, when they all fit: later rows cost no search.
// When they do not fit, nothing but the measured row is computed; a deadline stops the batches.
TEST(DistTable, EveryCellsRowWhenTheyAllFit) {
  const Grid g = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/random-32-32-20.map");
  const size_t f = g.free_cells().size();
  DistTable big(g, ActionModel::kRotation, size_t(64) << 20);
  const auto all = big.prefetch_all();
  EXPECT_TRUE(all.fit);
  EXPECT_EQ(all.computed, f);
  EXPECT_EQ(big.cached_rows(), f);
  EXPECT_EQ(big.bfs_count(), f);
  EXPECT_EQ(all.bytes, big.cached_bytes());
  for (size_t i = 0; i < f; i += 17) big.row(g.free_cells()[i]);
  EXPECT_EQ(big.bfs_count(), f) << "no row computed again";

  DistTable small(g, ActionModel::kRotation, all.bytes / 2);
  const auto half = small.prefetch_all();
  EXPECT_FALSE(half.fit);
  EXPECT_EQ(half.computed, 0u);
  EXPECT_LE(small.bfs_count(), 1u);

  DistTable late(g, ActionModel::kRotation, size_t(64) << 20);
  const auto cut = late.prefetch_all(std::chrono::steady_clock::now());
  EXPECT_TRUE(cut.fit);
  EXPECT_LT(cut.computed, f);
  EXPECT_EQ(late.cached_rows(), cut.computed);
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
  EXPECT_EQ(d.cached_bytes(), 2 * d.row_bytes());
}

TEST(DistTable, RowsAreSixteenBitsPerFreeCell) {
  // warehouse-10-20-10-2-1: every row is 2 bytes per free cell (plus one sentinel slot), not
  // 4 bytes per grid cell.
  Grid g = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/warehouse-10-20-10-2-1.map");
  DistTable d(g);
  auto row = d.row(g.free_cells()[0]);
  EXPECT_EQ(row->bytes(), sizeof(DistRow) + (g.free_cells().size() + 1) * 2);
  EXPECT_LT(row->bytes(), size_t(g.num_cells()) * 4 / 2);
}

TEST(DistTable, BudgetHoldsUnderManyDistinctGoals) {
  Grid g = Grid::from_rows(std::vector<std::string>(30, std::string(30, '.')));
  DistTable probe(g);
  const size_t budget = 10 * probe.row_bytes();
  DistTable d(g, budget);
  auto held = d.row(g.cell(0, 0));  // a row kept by a solver survives eviction
  for (size_t i = 1; i < g.free_cells().size(); ++i) {
    d.get(g.free_cells()[i], 0);
    ASSERT_LE(d.cached_bytes(), budget) << "after " << i << " goals";
    ASSERT_LE(d.cached_rows(), 10u);
  }
  EXPECT_LE(d.peak_bytes(), budget);
  EXPECT_EQ(d.bfs_count(), g.free_cells().size());
  EXPECT_GT(d.evictions(), 800u);
  EXPECT_EQ(d.over_budget_inserts(), 0u);
  EXPECT_EQ((*held)[g.cell(3, 4)], 7);
  // The held row is still the cached one: asking again costs no BFS.
  const auto bfs_before = d.bfs_count();
  EXPECT_EQ(d.row(g.cell(0, 0)), held);
  EXPECT_EQ(d.bfs_count(), bfs_before);
  // has() tells the cached rows from the evicted ones, without counting as a use.
  EXPECT_TRUE(d.has(g.cell(0, 0)));
  EXPECT_TRUE(d.has(g.free_cells().back()));
  EXPECT_FALSE(d.has(g.cell(1, 0)));
  EXPECT_EQ(d.bfs_count(), bfs_before);
  // Evicted rows are recomputed with the same answer.
  EXPECT_EQ(d.get(g.cell(1, 0), g.cell(29, 29)), 28 + 29);
  EXPECT_TRUE(d.has(g.cell(1, 0)));
}

TEST(DistTable, HeldRowsAreNeverEvictedAndAreCounted) {
  // Solvers hold 20 rows at once with a budget for 10: the cache keeps all 20 (they are live
  // memory anyway), says so, and returns under budget once they are released.
  Grid g = Grid::from_rows(std::vector<std::string>(20, std::string(20, '.')));
  DistTable probe(g);
  const size_t budget = 10 * probe.row_bytes();
  DistTable d(g, budget);
  std::vector<std::shared_ptr<const DistRow>> held;
  for (int i = 0; i < 20; ++i) held.push_back(d.row(g.free_cells()[i]));
  EXPECT_EQ(d.cached_rows(), 20u);
  EXPECT_EQ(d.cached_bytes(), 20 * d.row_bytes());
  EXPECT_GT(d.over_budget_inserts(), 0u);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(d.row(g.free_cells()[i]), held[i]);
  EXPECT_EQ(d.bfs_count(), 20u);
  held.clear();
  for (int i = 20; i < 60; ++i) d.row(g.free_cells()[i]);
  EXPECT_LE(d.cached_bytes(), budget);
}

TEST(DistTable, PrefetchComputesMissingRowsOnceInParallel) {
  Grid g = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/random-32-32-20.map");
  DistTable d(g);
  std::vector<Cell> goals;
  for (size_t i = 0; i < g.free_cells().size(); i += 3) goals.push_back(g.free_cells()[i]);
  goals.push_back(goals[0]);  // duplicates cost one BFS
  d.get(goals[1], goals[2]);
  d.prefetch(goals);
  EXPECT_EQ(d.bfs_count(), goals.size() - 1);
  EXPECT_EQ(d.cached_rows(), goals.size() - 1);
  auto rows = d.rows(goals);
  EXPECT_EQ(d.bfs_count(), goals.size() - 1);  // all cached
  ASSERT_EQ(rows.size(), goals.size());
  for (size_t k = 0; k < goals.size(); k += 17) {
    const auto ref = plain_bfs(g, goals[k]);
    EXPECT_EQ(rows[k]->goal(), goals[k]);
    for (Cell c = 0; c < g.num_cells(); ++c) ASSERT_EQ((*rows[k])[c], ref[c]);
  }
}

TEST(DistTable, PrefetchRespectsTheBudget) {
  Grid g = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/random-32-32-20.map");
  DistTable probe(g);
  const size_t budget = 25 * probe.row_bytes();
  DistTable d(g, budget);
  std::vector<Cell> goals(g.free_cells().begin(), g.free_cells().begin() + 200);
  d.prefetch(goals);
  EXPECT_LE(d.cached_bytes(), budget);
  EXPECT_LE(d.peak_bytes(), budget);
  EXPECT_EQ(d.bfs_count(), 200u);
}

TEST(DistTable, RowOutlivesItsTable) {
  Grid g = Grid::from_rows({"...", ".@.", "..."});
  std::shared_ptr<const DistRow> row;
  {
    DistTable d(g);
    row = d.row(g.cell(0, 0));
  }
  EXPECT_EQ((*row)[g.cell(2, 2)], 4);
  EXPECT_GE((*row)[g.cell(1, 1)], kUnreachable);
}

TEST(DistTable, ConcurrentQueriesAgree) {
  Grid g = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/random-32-32-20.map");
  DistTable probe(g);
  DistTable d(g, 20 * probe.row_bytes());  // small budget: eviction races with lookups
  std::vector<std::thread> threads;
  std::vector<long> sums(4, 0);
  for (int t = 0; t < 4; ++t)
    threads.emplace_back([&, t] {
      for (size_t i = 0; i < g.free_cells().size(); i += 7) {
        sums[t] += d.get(g.free_cells()[i], g.free_cells()[0]);
        if (t == 3 && i % 70 == 0) {  // one thread warms batches at the same time
          std::vector<Cell> batch(g.free_cells().begin() + i, g.free_cells().begin() + std::min(i + 8, g.free_cells().size()));
          d.prefetch(batch);
        }
      }
    });
  for (auto& th : threads) th.join();
  for (int t = 1; t < 4; ++t) EXPECT_EQ(sums[t], sums[0]);
  EXPECT_GT(sums[0], 0);
  long ref = 0;
  const auto from0 = plain_bfs(g, g.free_cells()[0]);
  for (size_t i = 0; i < g.free_cells().size(); i += 7) ref += from0[g.free_cells()[i]];  // symmetric
  EXPECT_EQ(sums[0], ref);
}

// Every row is a shortest-path table under the step costs (a turn 1, a forward move in heading h
// into a cell its cost), checked state by state (Bellman's equation) for goals picked by rng.
static void expect_rows_shortest_under_costs(const Grid& g, const std::shared_ptr<const FreeCellIndex>& ix,
                                      std::mt19937_64& rng) {
  for (int k = 0; k < 5; ++k) {
    const Cell goal = g.free_cells()[rng() % g.free_cells().size()];
    const DistRow row(ix, goal);
    for (Cell c : g.free_cells())
      for (Heading h = 0; h < kNumHeadings; ++h) {
        const int d = row.at(c, h);
        if (c == goal) {
          EXPECT_EQ(d, 0);
          continue;
        }
        if (d >= kUnreachable) continue;
        int best = std::min(row.at(c, (h + 1) % 4), row.at(c, (h + 3) % 4)) + 1;
        const Cell f = forward_cell(g, c, h);
        if (f != kNoCell && row.at(f, h) < kUnreachable)
          best = std::min(best, ix->cost[ix->slot_of[f] * kNumHeadings + h] + row.at(f, h));
        EXPECT_EQ(d, best) << "cell " << c << " heading " << int(h);
      }
  }
}

// Traffic cost (rotation): rows are shortest under the costs on random maps; costs lie in
// [1, 1 + strength], the same from every heading.
TEST(DistTable, TrafficCostRowsAreShortestUnderTheCosts) {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 4; ++trial) {
    const Grid g = random_map(20, 16, 0.2, rng);
    auto ix = std::make_shared<const FreeCellIndex>(g, std::vector<Cell>{}, ActionModel::kRotation,
                                                    StepCosts{2.0, 0.0});
    ASSERT_EQ(static_cast<int>(ix->cost.size()), ix->num_free * kNumHeadings);
    EXPECT_EQ(ix->max_cost, 3);
    for (uint8_t c : ix->cost) EXPECT_TRUE(c >= 1 && c <= 3);
    expect_rows_shortest_under_costs(g, ix, rng);
  }
}

TEST(DistTable, TrafficCostIsHighestOnTheOnlyDoorAndRotationOnly) {
  // Two rooms joined by one door at (4, 2): every path between them crosses it.
  const Grid g = Grid::from_rows({"....@....", "....@....", ".........", "....@....", "....@...."});
  FreeCellIndex ix(g, {}, ActionModel::kRotation, StepCosts{4.0, 0.0});
  const auto into = [&](Cell c) { return int(ix.cost[ix.slot_of[c] * kNumHeadings + kEast]); };
  const int door = into(g.cell(4, 2));
  EXPECT_EQ(door, 5);
  EXPECT_LT(into(g.cell(0, 0)), door);
  for (Heading h = 0; h < kNumHeadings; ++h) EXPECT_EQ(ix.cost[ix.slot_of[g.cell(4, 2)] * kNumHeadings + h], door);
  EXPECT_THROW(FreeCellIndex(g, {}, ActionModel::kMapf, StepCosts{1.0, 0.0}), std::invalid_argument);
  EXPECT_THROW(FreeCellIndex(g, {}, ActionModel::kMapf, StepCosts{0.0, 2.0}), std::invalid_argument);
  FreeCellIndex none(g, {}, ActionModel::kRotation, StepCosts{});
  EXPECT_TRUE(none.cost.empty());
  FreeCellIndex no_lanes(g, {}, ActionModel::kRotation, StepCosts{0.0, 2.0});  // no one-cell aisle
  EXPECT_TRUE(no_lanes.cost.empty());
}

// Step costs raise the bound on a distance, so a big open map's index calls for 32-bit rows
// (22,500 free cells x (3 + 1)); every row's distances fit in 16 bits, and it is kept in 16,
// its Bellman equations as before. The serpentine's distances pass 65,535: 32 bits.
TEST(DistTable, RowsWithStepCostsAreSixteenBitsWhenTheirDistancesFit) {
  const Grid open = Grid::from_rows(std::vector<std::string>(150, std::string(150, '.')));
  auto ix = std::make_shared<const FreeCellIndex>(open, std::vector<Cell>{}, ActionModel::kRotation,
                                                  StepCosts{2.0, 0.0});
  ASSERT_TRUE(ix->wide());
  const DistRow row(ix, open.cell(75, 75));
  EXPECT_TRUE(row.narrow());
  EXPECT_EQ(row.bytes(), sizeof(DistRow) + (open.free_cells().size() + 1) * 3);
  std::mt19937_64 rng(5);
  expect_rows_shortest_under_costs(open, ix, rng);

  std::vector<std::string> rows(480, std::string(300, '.'));
  for (int y = 1; y < 480; y += 2) {
    rows[y] = std::string(300, '@');
    rows[y][(y / 2) % 2 ? 0 : 299] = '.';
  }
  const Grid serpentine = Grid::from_rows(rows);
  auto far = std::make_shared<const FreeCellIndex>(serpentine, std::vector<Cell>{}, ActionModel::kRotation,
                                                   StepCosts{2.0, 0.0});
  const DistRow long_row(far, serpentine.cell(0, 0));
  EXPECT_FALSE(long_row.narrow());
  EXPECT_GT(long_row.at(serpentine.cell(299, 478), kEast), 65535);
}

// Lane cost (rotation): on shelves with one-cell aisles (lanes east, west, east, west), a move
// against an aisle's lane costs 1 + 2, so going east along the westbound aisle takes the
// eastbound one next to it (18 steps with the turns) instead of 11 moves at 3 each; rows stay
// shortest under the costs with the traffic cost added too.
TEST(DistTable, LaneCostSendsTrafficAlongTheNextAisleTheOtherWay) {
  const Grid g = Grid::from_rows({"............", ".@@@@@@@@@@.", "............", ".@@@@@@@@@@.",
                                  "............", ".@@@@@@@@@@.", "............"});
  auto lanes = std::make_shared<const FreeCellIndex>(g, std::vector<Cell>{}, ActionModel::kRotation,
                                                     StepCosts{0.0, 2.0});
  auto plain = std::make_shared<const FreeCellIndex>(g, std::vector<Cell>{}, ActionModel::kRotation);
  const Cell west = g.cell(0, 2), east = g.cell(11, 2);  // the ends of the westbound aisle
  EXPECT_EQ(DistRow(lanes, west).at(east, kWest), 11);  // with the lane
  EXPECT_EQ(DistRow(lanes, east).at(west, kEast), 18);  // north, along the eastbound aisle, south
  EXPECT_EQ(DistRow(plain, east).at(west, kEast), 11);
  EXPECT_EQ(lanes->max_cost, 3);
  std::mt19937_64 rng(3);
  expect_rows_shortest_under_costs(g, lanes, rng);
  auto both = std::make_shared<const FreeCellIndex>(g, std::vector<Cell>{}, ActionModel::kRotation,
                                                    StepCosts{2.0, 2.0});
  expect_rows_shortest_under_costs(g, both, rng);
}

// Open cost (rotation): a band two rows high above shelves with three one-cell aisles. From the west end
// of the aisle in row 3, facing north, the goal at the band's east end is 14 steps away along the
// band (3 north, a turn, 10 east) and 15 along the aisle (a turn, 10 east, a turn, 3 north). With
// open-cost 2 each of the band's 10 moves east costs 3, so the row leads along the aisle; crossing
// the band (north in column 0) costs nothing more.
TEST(DistTable, OpenCostSendsTravelAlongTheAislesAndAcrossTheBand) {
  const Grid g = Grid::from_rows({"...........", "...........", ".@@@@@@@@@.", "...........", ".@@@@@@@@@.",
                                  "...........", ".@@@@@@@@@.", "..........."});
  StepCosts costs;
  costs.open = 2;
  auto open = std::make_shared<const FreeCellIndex>(g, std::vector<Cell>{}, ActionModel::kRotation, costs);
  auto plain = std::make_shared<const FreeCellIndex>(g, std::vector<Cell>{}, ActionModel::kRotation);
  const Cell start = g.cell(0, 3), goal = g.cell(10, 0);
  EXPECT_EQ(DistRow(plain, goal).at(start, kNorth), 14);
  EXPECT_EQ(DistRow(open, goal).at(start, kNorth), 15);
  EXPECT_EQ(DistRow(open, g.cell(0, 0)).at(g.cell(0, 7), kNorth), 7);
  EXPECT_EQ(open->max_cost, 3);
  std::mt19937_64 rng(11);
  expect_rows_shortest_under_costs(g, open, rng);
  EXPECT_THROW(FreeCellIndex(g, {}, ActionModel::kMapf, costs), std::invalid_argument);
}
