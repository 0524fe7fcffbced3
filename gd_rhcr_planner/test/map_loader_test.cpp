// map_server YAML + PGM loading and the metric frame, without a ROS master.
#include <cstdio>
#include <fstream>
#include <string>

#include <gtest/gtest.h>

#include "gd_rhcr_planner/map_loader.hpp"

using namespace gd_rhcr_planner;

namespace {
std::string tmp_dir() {
  static std::string dir = [] {
    char tmpl[] = "/tmp/gd_rhcr_maptest_XXXXXX";
    return std::string(mkdtemp(tmpl));
  }();
  return dir;
}
void write(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}
}  // namespace

TEST(MapLoader, ReadsP5AndYamlWithTopRowFirst) {
  // 3x2 image: top row free, free, black; bottom row black, free, grey (unknown).
  std::string pgm = "P5\n# comment\n3 2\n255\n";
  pgm += std::string{char(254), char(254), char(0), char(0), char(254), char(205)};
  write(tmp_dir() + "/m.pgm", pgm);
  write(tmp_dir() + "/m.yaml",
        "image: m.pgm\nresolution: 0.5\norigin: [1.0, -2.0, 0.0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  LoadedMap m = load_map(tmp_dir() + "/m.yaml", 99.0);
  EXPECT_EQ(m.format, "map_server");
  ASSERT_EQ(m.grid.width(), 3);
  ASSERT_EQ(m.grid.height(), 2);
  EXPECT_TRUE(m.grid.is_free(m.grid.cell(0, 0)));
  EXPECT_TRUE(m.grid.is_free(m.grid.cell(1, 0)));
  EXPECT_FALSE(m.grid.is_free(m.grid.cell(2, 0)));
  EXPECT_FALSE(m.grid.is_free(m.grid.cell(0, 1)));
  EXPECT_TRUE(m.grid.is_free(m.grid.cell(1, 1)));
  EXPECT_FALSE(m.grid.is_free(m.grid.cell(2, 1)));  // unknown counts as blocked
  EXPECT_DOUBLE_EQ(m.frame.resolution, 0.5);
  // Cell (0,0) is the top-left: the largest y in the map frame.
  EXPECT_DOUBLE_EQ(m.frame.world_x(0), 1.25);
  EXPECT_DOUBLE_EQ(m.frame.world_y(0), -2.0 + 1.5 * 0.5);
  EXPECT_DOUBLE_EQ(m.frame.world_y(1), -2.0 + 0.5 * 0.5);
  EXPECT_EQ(m.frame.cell_x(m.frame.world_x(2)), 2);
  EXPECT_EQ(m.frame.cell_y(m.frame.world_y(1)), 1);
}

TEST(MapLoader, ReadsAsciiP2AndNegate) {
  write(tmp_dir() + "/a.pgm", "P2\n2 1\n15\n0 15\n");
  write(tmp_dir() + "/a.yaml", "image: a.pgm\nresolution: 1\nnegate: 1\n");
  LoadedMap m = load_map(tmp_dir() + "/a.yaml", 1.0);
  EXPECT_TRUE(m.grid.is_free(0));   // negate: black is free
  EXPECT_FALSE(m.grid.is_free(1));
}

TEST(MapLoader, MovingAiAndKivaUseCellSize) {
  LoadedMap w = load_map(std::string(GD_RHCR_MAPS_DIR) + "/warehouse-10-20-10-2-1.map", 0.8);
  EXPECT_EQ(w.format, "movingai");
  EXPECT_EQ(w.grid.width(), 161);
  EXPECT_DOUBLE_EQ(w.frame.resolution, 0.8);
  LoadedMap k = load_map(std::string(GD_RHCR_MAPS_DIR) + "/kiva.map", 1.0);
  EXPECT_EQ(k.format, "kiva");
}

TEST(MapLoader, ShippedPgmMatchesItsMovingAiSource) {
  LoadedMap a = load_map(std::string(GD_RHCR_MAPS_DIR) + "/warehouse-10-20-10-2-1.map", 1.0);
  LoadedMap b = load_map(std::string(GD_RHCR_MAPS_DIR) + "/warehouse-10-20-10-2-1.yaml", 1.0);
  ASSERT_EQ(a.grid.num_cells(), b.grid.num_cells());
  for (int c = 0; c < a.grid.num_cells(); ++c) ASSERT_EQ(a.grid.is_free(c), b.grid.is_free(c)) << c;
}

TEST(MapLoader, ErrorsNameTheFile) {
  write(tmp_dir() + "/bad.yaml", "image: missing.pgm\nresolution: 1\n");
  try {
    load_map(tmp_dir() + "/bad.yaml", 1.0);
    FAIL() << "expected MapError";
  } catch (const gdrhcr::MapError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.pgm"), std::string::npos) << e.what();
  }
  write(tmp_dir() + "/noimage.yaml", "resolution: 1\n");
  EXPECT_THROW(load_map(tmp_dir() + "/noimage.yaml", 1.0), gdrhcr::MapError);
  write(tmp_dir() + "/t.pgm", "P5\n3 3\n255\n");
  write(tmp_dir() + "/t.yaml", "image: t.pgm\nresolution: 1\n");
  EXPECT_THROW(load_map(tmp_dir() + "/t.yaml", 1.0), gdrhcr::MapError);  // truncated data
  write(tmp_dir() + "/p6.pgm", "P6\n1 1\n255\nabc");
  write(tmp_dir() + "/p6.yaml", "image: p6.pgm\nresolution: 1\n");
  EXPECT_THROW(load_map(tmp_dir() + "/p6.yaml", 1.0), gdrhcr::MapError);
  EXPECT_THROW(load_map(tmp_dir() + "/m.yaml", 0.0), gdrhcr::MapError);
}
