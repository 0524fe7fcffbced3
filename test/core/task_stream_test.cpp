// Task streams are seeded per agent, MAPD alternates sets, starts are distinct free cells.
#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }
}

TEST(TaskStream, RandomGoalsAreFreeAndDifferFromCurrent) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  RandomNavigationStream s(g, 5);
  Cell cur = g.free_cells()[0];
  for (int k = 0; k < 500; ++k) {
    Cell next = s.next_goal(3, cur);
    EXPECT_TRUE(g.is_free(next));
    EXPECT_NE(next, cur);
    cur = next;
  }
}

TEST(TaskStream, SequencePerAgentIndependentOfCallOrder) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  RandomNavigationStream a(g, 9), b(g, 9);
  std::vector<Cell> seq_a, seq_b;
  for (int k = 0; k < 10; ++k) seq_a.push_back(a.next_goal(2, 0));
  for (int k = 0; k < 10; ++k) {
    b.next_goal(0, 0);  // interleaved calls for other agents must not disturb agent 2
    seq_b.push_back(b.next_goal(2, 0));
    b.next_goal(5, 0);
  }
  EXPECT_EQ(seq_a, seq_b);
  RandomNavigationStream c(g, 10);
  std::vector<Cell> seq_c;
  for (int k = 0; k < 10; ++k) seq_c.push_back(c.next_goal(2, 0));
  EXPECT_NE(seq_a, seq_c);  // another seed, another sequence
  auto fresh = a.clone_fresh();
  EXPECT_EQ(fresh->next_goal(2, 0), seq_a[0]);
}

TEST(TaskStream, MapdAlternatesPickupAndDelivery) {
  Grid g = Grid::load(repo("maps/kiva.map"));
  MapdCells cells = default_mapd_cells(g);
  EXPECT_EQ(cells.pickups.size(), 480u);
  EXPECT_EQ(cells.deliveries.size(), 192u);
  PickupDeliveryStream s(g, cells.pickups, cells.deliveries, 1);
  std::set<Cell> pick(cells.pickups.begin(), cells.pickups.end());
  std::set<Cell> del(cells.deliveries.begin(), cells.deliveries.end());
  Cell cur = g.free_cells()[0];
  for (int k = 0; k < 20; ++k) {
    cur = s.next_goal(0, cur);
    EXPECT_TRUE((k % 2 == 0 ? pick : del).count(cur)) << k;
  }
}

TEST(TaskStream, WarehouseMapdRule) {
  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  MapdCells cells = default_mapd_cells(g);
  ASSERT_FALSE(cells.pickups.empty());
  ASSERT_FALSE(cells.deliveries.empty());
  int min_x = g.width(), max_x = 0;
  for (Cell c : g.free_cells()) min_x = std::min(min_x, g.x_of(c)), max_x = std::max(max_x, g.x_of(c));
  for (Cell c : cells.deliveries) EXPECT_TRUE(g.x_of(c) == min_x || g.x_of(c) == max_x);
  for (Cell c : cells.pickups) {
    EXPECT_TRUE(g.is_free(c));
    EXPECT_LT(g.neighbours(c).size(), 4);  // beside a shelf
  }
}

TEST(TaskStream, CellListFileErrors) {
  Grid g = Grid::from_rows({"..", ".@"});
  const std::string path = testing::TempDir() + "/cells.txt";
  auto write = [&](const std::string& text) { std::ofstream(path) << text; };
  write("# pickups\n0 0\n1,0\n");
  EXPECT_EQ(load_cell_list(g, path), (std::vector<Cell>{g.cell(0, 0), g.cell(1, 0)}));
  write("0 0\n1 1\n");
  try { load_cell_list(g, path); FAIL(); } catch (const MapError& e) {
    EXPECT_NE(std::string(e.what()).find(":2: cell (1,1) is an obstacle"), std::string::npos) << e.what();
  }
  write("5 0\n");
  EXPECT_THROW(load_cell_list(g, path), MapError);
  write("zero zero\n");
  EXPECT_THROW(load_cell_list(g, path), MapError);
}

TEST(TaskStream, RandomStartsDistinctAndBounded) {
  Grid g = Grid::from_rows({"...", ".@.", "..."});
  auto s = random_starts(g, 8, 3);
  EXPECT_EQ(std::set<Cell>(s.begin(), s.end()).size(), 8u);
  for (Cell c : s) EXPECT_TRUE(g.is_free(c));
  EXPECT_EQ(random_starts(g, 8, 3), s);  // seeded
  EXPECT_THROW(random_starts(g, 9, 3), std::invalid_argument);
  EXPECT_THROW(random_starts(g, 0, 3), std::invalid_argument);
}

TEST(TaskStream, GeneratedSortationMapsHaveReachableSideFiles) {
  // tools/gen_maps.py output: sizes, one connected component, and every pickup and delivery
  // cell free (load_cell_list throws otherwise) and reachable.
  struct { const char* name; int w, h; } maps[] = {{"sortation-1", 203, 91}, {"sortation-2", 127, 57}};
  for (auto& m : maps) {
    const std::string path = repo(std::string("maps/") + m.name + ".map");
    Grid g = Grid::load(path);
    EXPECT_EQ(g.width(), m.w);
    EXPECT_EQ(g.height(), m.h);
    EXPECT_EQ(g.count_components(), 1) << m.name;
    MapdCells cells = mapd_cells_for_map(g, path);
    EXPECT_NE(cells.rule.find("side files"), std::string::npos);
    EXPECT_GT(cells.pickups.size(), 100u);
    EXPECT_GT(cells.deliveries.size(), 500u);
    EXPECT_GE(g.free_cells().size(), 4000u);  // room for 1000 agents
  }
}

TEST(TaskStream, GeneratedRoomVariantsAreConnected) {
  for (const char* name : {"room-32-32-var1", "room-64-64-var1", "room-64-64-var2"}) {
    Grid g = Grid::load(repo(std::string("maps/") + name + ".map"));
    EXPECT_EQ(g.count_components(), 1) << name;
  }
  // var2 has wider openings than var1 on the same rooms: more free cells.
  EXPECT_GT(Grid::load(repo("maps/room-64-64-var2.map")).free_cells().size(),
            Grid::load(repo("maps/room-64-64-var1.map")).free_cells().size());
}
