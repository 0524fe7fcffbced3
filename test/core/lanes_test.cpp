// One-way lanes derived from the map (lanes.hpp): aisles one cell wide between shelves get
// alternating directions, open areas and random maps get none.
#include <gtest/gtest.h>

#include "gdrhcr/lanes.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }
}  // namespace

TEST(Lanes, AislesBetweenShelvesAlternateAndOpenAreasHaveNone) {
  // Rows 0, 2, 4, 6 are aisles between shelf rows; rows 7-8 are an open area two rows high;
  // columns 0 and 11 run past the shelf ends, and every column is at least half free.
  const Grid g = Grid::from_rows({"............", ".@@@@@@@@@@.", "............", ".@@@@@@@@@@.",
                                  "............", ".@@@@@@@@@@.", "............", "@@@@@@@@@@@@",
                                  "............", "............"});
  const Lanes l = derive_lanes(g);
  const std::vector<Heading> rows = {kEast, kNoHeading, kWest, kNoHeading, kEast, kNoHeading, kWest,
                                     kNoHeading, kNoHeading, kNoHeading};
  EXPECT_EQ(l.row, rows);
  EXPECT_EQ(l.col, std::vector<Heading>(12, kNoHeading));
  EXPECT_EQ(l.num_lanes(), 4);
  EXPECT_TRUE(l.against(g, g.cell(5, 2), kEast));  // row 2 goes west
  EXPECT_FALSE(l.against(g, g.cell(5, 2), kWest));
  EXPECT_FALSE(l.against(g, g.cell(0, 3), kNorth));  // no column lanes
  EXPECT_FALSE(l.against(g, g.cell(5, 8), kWest));   // open area
}

TEST(Lanes, ColumnsOfOneCellAisles) {
  // The transposed layout: aisles are columns 0, 2, 4 (south, north, south).
  const Grid g = Grid::from_rows({".....", ".@.@.", ".@.@.", ".@.@.", ".@.@.", "....."});
  const Lanes l = derive_lanes(g);
  EXPECT_EQ(l.col, (std::vector<Heading>{kSouth, kNoHeading, kNorth, kNoHeading, kSouth}));
  EXPECT_TRUE(l.against(g, g.cell(2, 3), kSouth));
  EXPECT_FALSE(l.against(g, g.cell(2, 3), kNorth));
}

TEST(Lanes, TheBenchmarkMapsTheirStructureCalls) {
  // Warehouses with one-cell aisles get lanes along them: rows and columns, or rows only where
  // the cross aisles are two cells wide (lorr-warehouse-140-500). Random, room and empty maps,
  // and warehouses whose aisles are all two cells wide, get none.
  struct Case {
    const char* map;
    bool rows, cols;
  };
  for (const Case& c : {Case{"maps/warehouse-10-20-10-2-1.map", true, true}, Case{"maps/sortation-1.map", true, true},
                        Case{"maps/lorr-warehouse-140-500.map", true, false},
                        Case{"maps/random-32-32-20.map", false, false}, Case{"maps/room-64-64-8.map", false, false},
                        Case{"maps/empty-48-48.map", false, false},
                        Case{"maps/warehouse-10-20-10-2-2.map", false, false}}) {
    const Lanes l = derive_lanes(Grid::load(repo(c.map)));
    int rows = 0, cols = 0;
    for (Heading h : l.row) rows += h != kNoHeading;
    for (Heading h : l.col) cols += h != kNoHeading;
    EXPECT_EQ(rows > 5, c.rows) << c.map << ": " << rows << " row lanes";
    EXPECT_EQ(cols > 5, c.cols) << c.map << ": " << cols << " column lanes";
    if (!c.rows) EXPECT_EQ(rows, 0) << c.map;
    if (!c.cols) EXPECT_EQ(cols, 0) << c.map;
  }
}

TEST(Lanes, TheLinesStyleAlternatesEveryRowAndColumn) {
  // Every row and column one can travel along is a lane, alternating; one obstacle does not
  // close a line.
  const Grid g = Grid::from_rows({"......", ".@....", "......", "......", "......", "......"});
  const Lanes l = derive_lanes(g, LaneStyle::kLines);
  EXPECT_EQ(l.row, (std::vector<Heading>{kEast, kWest, kEast, kWest, kEast, kWest}));
  EXPECT_EQ(l.col, (std::vector<Heading>{kSouth, kNorth, kSouth, kNorth, kSouth, kNorth}));
  EXPECT_TRUE(l.against(g, g.cell(2, 1), kEast));   // row 1 goes west
  EXPECT_TRUE(l.against(g, g.cell(2, 2), kNorth));  // column 2 goes south
  EXPECT_FALSE(l.against(g, g.cell(2, 2), kEast));
  EXPECT_EQ(derive_lanes(g).num_lanes(), 0);  // no aisles here
}

TEST(Lanes, TheLinesStyleSkipsLinesTheObstaclesBreak) {
  // A sortation-like lattice: every other row and column has an obstacle in every other cell.
  // Those lines are no lanes, and the open ones alternate among themselves, so both directions
  // get open lines (by parity every open row would go east and every open column south).
  const Grid g = Grid::from_rows({".......", ".@.@.@.", ".......", ".@.@.@.", ".......", ".@.@.@.", "......."});
  const Lanes l = derive_lanes(g, LaneStyle::kLines);
  EXPECT_EQ(l.row, (std::vector<Heading>{kEast, kNoHeading, kWest, kNoHeading, kEast, kNoHeading, kWest}));
  EXPECT_EQ(l.col, (std::vector<Heading>{kSouth, kNoHeading, kNorth, kNoHeading, kSouth, kNoHeading, kNorth}));
  EXPECT_FALSE(l.against(g, g.cell(2, 1), kWest));  // no lane along row 1: any way is as cheap
  EXPECT_FALSE(l.against(g, g.cell(2, 1), kEast));
  EXPECT_TRUE(l.against(g, g.cell(3, 2), kEast));   // row 2 goes west
}

TEST(Lanes, OpenAreasAreTheWideRunsOnAnAxisWithAisles) {
  // Rows 0, 2, 4, 6 are aisles and rows 8-9 an open area two rows high: an open area. Every column
  // is at least half free, one run with no aisle among them: no open area across the columns.
  const Grid g = Grid::from_rows({"............", ".@@@@@@@@@@.", "............", ".@@@@@@@@@@.",
                                  "............", ".@@@@@@@@@@.", "............", "@@@@@@@@@@@@",
                                  "............", "............"});
  const OpenAreas a = derive_open_areas(g);
  EXPECT_EQ(a.row, (std::vector<char>{0, 0, 0, 0, 0, 0, 0, 0, 1, 1}));
  EXPECT_EQ(a.col, std::vector<char>(12, 0));
  EXPECT_EQ(a.num_lines(), 2);
  EXPECT_TRUE(a.along(g, g.cell(5, 8), kEast));
  EXPECT_TRUE(a.along(g, g.cell(5, 9), kWest));
  EXPECT_FALSE(a.along(g, g.cell(5, 9), kNorth));  // crossing it
  EXPECT_FALSE(a.along(g, g.cell(5, 2), kEast));   // an aisle
  // Without aisles every open line is in one wide run, and there are no open areas at all.
  EXPECT_EQ(derive_open_areas(Grid::from_rows({"....", "....", ".@..", "...."})).num_lines(), 0);
}

TEST(Lanes, TheBenchmarkMapsOpenAreas) {
  // lorr-warehouse-140-500: the bands above and below the shelves (rows 0-2, 137-139), crossed by
  // 44 aisles; its columns have no aisles. sortation-1: the bands at its four edges, two lines
  // each; the highways five columns wide between its shelf blocks lie between aisles and are no
  // open areas. warehouse-10-20-10-2-1's open columns are its side rooms, 50 columns against 9
  // aisles: the main travel space. Random, room and empty maps have no aisles, hence no open areas.
  const OpenAreas w = derive_open_areas(Grid::load(repo("maps/lorr-warehouse-140-500.map")));
  for (int y = 0; y < 140; ++y) EXPECT_EQ(w.row[y], y <= 2 || y >= 137) << "row " << y;
  EXPECT_EQ(w.col, std::vector<char>(500, 0));
  const OpenAreas s = derive_open_areas(Grid::load(repo("maps/sortation-1.map")));
  for (int y = 0; y < 91; ++y) EXPECT_EQ(s.row[y], y <= 1 || y >= 89) << "row " << y;
  for (int x = 0; x < 203; ++x) EXPECT_EQ(s.col[x], x <= 1 || x >= 201) << "column " << x;
  for (const char* map : {"maps/warehouse-10-20-10-2-1.map", "maps/random-32-32-20.map", "maps/room-64-64-8.map",
                          "maps/empty-48-48.map", "maps/warehouse-10-20-10-2-2.map"})
    EXPECT_EQ(derive_open_areas(Grid::load(repo(map))).num_lines(), 0) << map;
}
