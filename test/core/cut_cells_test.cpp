// Cut cells (cut_cells.hpp): articulation points of the grid graph.
#include <gtest/gtest.h>

#include "gdrhcr/cut_cells.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }
}  // namespace

TEST(CutCells, DeadEndBranchAndCorridor) {
  // A corridor with a dead-end branch: every inner corridor cell and the branch's upper cell
  // disconnect the map; the two ends and the branch's tip do not.
  Grid g = Grid::from_rows({".....", "@@.@@", "@@.@@"});
  const auto cut = cut_cells(g);
  for (int x = 1; x <= 3; ++x) EXPECT_EQ(cut[g.cell(x, 0)], 1) << x;
  EXPECT_EQ(cut[g.cell(0, 0)], 0);
  EXPECT_EQ(cut[g.cell(4, 0)], 0);
  EXPECT_EQ(cut[g.cell(2, 1)], 1);
  EXPECT_EQ(cut[g.cell(2, 2)], 0);
}

TEST(CutCells, RingAndOpenMapsHaveNone) {
  Grid ring = Grid::from_rows({".....", ".@@@.", "....."});
  EXPECT_EQ(cut_cell_share(ring), 0.0);
  EXPECT_EQ(cut_cell_share(Grid::load(repo("maps/empty-48-48.map"))), 0.0);
  EXPECT_EQ(cut_cell_share(Grid::load(repo("maps/warehouse-10-20-10-2-1.map"))), 0.0);
  EXPECT_GT(cut_cell_share(Grid::load(repo("maps/random-32-32-20.map"))), 0.01);
}

TEST(CutCells, EachComponentOnItsOwn) {
  // Two separate corridors of three cells: each middle cell is a cut cell of its component.
  Grid g = Grid::from_rows({"...", "@@@", "..."});
  const auto cut = cut_cells(g);
  EXPECT_EQ(cut[g.cell(1, 0)], 1);
  EXPECT_EQ(cut[g.cell(1, 2)], 1);
  EXPECT_EQ(cut[g.cell(0, 0)] + cut[g.cell(2, 0)] + cut[g.cell(0, 2)] + cut[g.cell(2, 2)], 0);
}
