// Map parsing: both formats, the tolerated symbols, and malformed files rejected with the line.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "gdrhcr/grid.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

Grid parse(const std::string& text) {
  std::istringstream in(text);
  return Grid::parse_movingai(in, "test.map");
}

std::string error_of(const std::string& text) {
  try {
    parse(text);
  } catch (const MapError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(Grid, LoadsWarehouseMap) {
  Grid g = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  EXPECT_EQ(g.width(), 161);
  EXPECT_EQ(g.height(), 63);
  EXPECT_EQ(g.free_cells().size(), 5699u);  // counts from ../shared/maps/SOURCES.md
  EXPECT_EQ(g.count_components(), 1);
}

TEST(Grid, LoadsAllShippedMovingAiMaps) {
  struct { const char* file; int w, h; size_t free; } maps[] = {
      {"maps/warehouse-10-20-10-2-2.map", 170, 84, 9776},
      {"maps/random-32-32-20.map", 32, 32, 819},
      {"maps/random-64-64-20.map", 64, 64, 3270},
      {"maps/empty-48-48.map", 48, 48, 2304},
      {"maps/room-32-32-4.map", 32, 32, 682},
      {"maps/room-64-64-8.map", 64, 64, 3232},
  };
  for (auto& m : maps) {
    Grid g = Grid::load(repo(m.file));
    EXPECT_EQ(g.width(), m.w) << m.file;
    EXPECT_EQ(g.height(), m.h) << m.file;
    EXPECT_EQ(g.free_cells().size(), m.free) << m.file;
  }
}

TEST(Grid, LoadsKivaMap) {
  Grid g = Grid::load(repo("maps/kiva.map"));
  EXPECT_EQ(g.height(), 33);
  EXPECT_EQ(g.width(), 46);
  EXPECT_EQ(g.free_cells().size(), 1278u);
  EXPECT_EQ(g.endpoints().size(), 480u);
  EXPECT_EQ(g.homes().size(), 192u);
  EXPECT_EQ(g.count_components(), 1);
}

TEST(Grid, SymbolsAndNeighbours) {
  Grid g = parse("type octile\nheight 3\nwidth 4\nmap\n.G@T\nS.OW\n....\n");
  EXPECT_TRUE(g.is_free(g.cell(0, 0)));
  EXPECT_TRUE(g.is_free(g.cell(1, 0)));   // G is free
  EXPECT_FALSE(g.is_free(g.cell(2, 0)));  // @
  EXPECT_FALSE(g.is_free(g.cell(3, 0)));  // T
  EXPECT_TRUE(g.is_free(g.cell(0, 1)));   // S (swamp) tolerated as free
  EXPECT_FALSE(g.is_free(g.cell(2, 1)));  // O
  EXPECT_FALSE(g.is_free(g.cell(3, 1)));  // W
  EXPECT_EQ(g.neighbours(g.cell(1, 1)).size(), 3);  // (0,1), (1,0), (1,2); (2,1) is blocked
  EXPECT_TRUE(g.step_allowed(g.cell(0, 0), g.cell(1, 0)));
  EXPECT_TRUE(g.step_allowed(g.cell(0, 0), g.cell(0, 0)));
  EXPECT_FALSE(g.step_allowed(g.cell(0, 0), g.cell(1, 1)));  // diagonal
  EXPECT_FALSE(g.step_allowed(g.cell(1, 0), g.cell(2, 0)));  // into an obstacle
}

TEST(Grid, ToleratesCrLfAndHeaderOrder) {
  Grid g = parse("type octile\r\nwidth 2\r\nheight 1\r\nmap\r\n..\r\n");
  EXPECT_EQ(g.width(), 2);
  EXPECT_EQ(g.height(), 1);
}

TEST(Grid, MalformedFilesNameTheLine) {
  EXPECT_NE(error_of("type octile\nheight 2\nwidth 3\nmap\n...\n..\n").find("test.map:6"), std::string::npos);
  EXPECT_NE(error_of("type octile\nheight 2\nwidth 3\nmap\n...\n..\n").find("width 3"), std::string::npos);
  EXPECT_NE(error_of("type octile\nheight 3\nwidth 2\nmap\n..\n..\n").find("truncated"), std::string::npos);
  EXPECT_NE(error_of("type octile\nheight x\nwidth 2\nmap\n..\n").find("test.map:2"), std::string::npos);
  EXPECT_NE(error_of("type octile\nheight 1\nwidth 2\nmap\n.#\n").find("unknown map symbol '#'"), std::string::npos);
  EXPECT_NE(error_of("type octile\nwidth 2\nmap\n..\n").find("missing 'height'"), std::string::npos);
  EXPECT_NE(error_of("type octile\nheight 1\nwidth 2\nmap\n@@\n").find("no free cell"), std::string::npos);
  EXPECT_NE(error_of("type octile\nheight 1\nwidth 2\nmap\n..\nextra\n").find("test.map:6"), std::string::npos);
  EXPECT_NE(error_of("type octile\nheight -1\nwidth 2\nmap\n..\n").find("positive"), std::string::npos);
}

TEST(Grid, MalformedKivaHeader) {
  std::istringstream in("33;46\n1\n1\n1\n");
  try {
    Grid::parse_kiva(in, "k.map");
    FAIL() << "accepted a bad header";
  } catch (const MapError& e) {
    EXPECT_NE(std::string(e.what()).find("k.map:1"), std::string::npos);
  }
}

TEST(Grid, MissingFileAndUnknownFormat) {
  EXPECT_THROW(Grid::load(repo("maps/no-such.map")), MapError);
  EXPECT_THROW(Grid::load(repo("README.md")), MapError);
}
