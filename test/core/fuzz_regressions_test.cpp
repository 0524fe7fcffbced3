// Replays every file in test/data/fuzz_regressions/ (inputs found by scripts/fuzz.sh, and the odd
// cases of issue 7: huge headers, binary garbage, empty files, lying kiva headers, ...) through
// each parser the fuzz targets drive. Each must either succeed or throw MapError, never crash or
// throw anything else; on success the parsed map must be consistent and its task streams must
// only hand out reachable goals.
#include <gtest/gtest.h>

#include <algorithm>
#include <dirent.h>
#include <fstream>
#include <sstream>

#include "gdrhcr/grid.hpp"
#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {

const std::string kDir = std::string(GDRHCR_SOURCE_DIR) + "/test/data/fuzz_regressions";

std::vector<std::string> regression_files() {
  std::vector<std::string> out;
  if (DIR* d = opendir(kDir.c_str())) {
    while (dirent* e = readdir(d))
      if (e->d_name[0] != '.') out.push_back(e->d_name);
    closedir(d);
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string read_all(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// Runs `parse`; returns true when it succeeded, false on MapError, and records a failure for
// any other exception.
template <class F>
bool succeeds_or_map_error(const std::string& what, F parse) {
  try {
    parse();
    return true;
  } catch (const MapError&) {
    return false;
  } catch (const std::exception& e) {
    ADD_FAILURE() << what << ": threw something other than MapError: " << e.what();
  } catch (...) {
    ADD_FAILURE() << what << ": threw a non-standard exception";
  }
  return false;
}

void check_parsed(const Grid& g, const std::string& what) {
  size_t total = 0;
  for (int k = 0; k < g.count_components(); ++k) {
    for (Cell c : g.component_cells(k)) ASSERT_EQ(g.component(c), k) << what;
    total += g.component_cells(k).size();
  }
  EXPECT_EQ(total, g.free_cells().size()) << what;
  const Cell start = g.free_cells()[g.free_cells().size() / 2];
  RandomNavigationStream random(g, 7);
  Cell cur = start;
  for (int k = 0; k < 10; ++k) {
    cur = random.next_goal(0, cur);
    EXPECT_EQ(g.component(cur), g.component(start)) << what;
  }
  MapdCells cells = default_mapd_cells(g);
  try {
    PickupDeliveryStream mapd(g, cells.pickups, cells.deliveries, 3);
    cur = start;
    for (int k = 0; k < 10; ++k) {
      cur = mapd.next_goal(0, cur);
      EXPECT_EQ(g.component(cur), g.component(start)) << what;
    }
  } catch (const std::invalid_argument&) {
    // unreachable sets or no pickup near the start: the documented error
  }
}

}  // namespace

TEST(FuzzRegressions, EveryFileParsesOrFailsWithMapError) {
  const auto files = regression_files();
  ASSERT_GE(files.size(), 10u) << "regression files missing from " << kDir;
  const Grid fixed = Grid::from_rows({"..@...", ".@@.e.", "......", "r@..@."}, "fixed");
  int parsed = 0;
  for (const auto& name : files) {
    SCOPED_TRACE(name);
    const std::string path = kDir + "/" + name;
    const std::string text = read_all(path);
    auto stream = [&] { return std::istringstream(text); };
    if (succeeds_or_map_error("Grid::load", [&] { check_parsed(Grid::load(path), name); })) ++parsed;
    succeeds_or_map_error("Grid::parse", [&] { auto in = stream(); check_parsed(Grid::parse(in, name), name); });
    succeeds_or_map_error("parse_movingai", [&] { auto in = stream(); Grid::parse_movingai(in, name); });
    succeeds_or_map_error("parse_kiva", [&] { auto in = stream(); Grid::parse_kiva(in, name); });
    succeeds_or_map_error("parse_cell_list", [&] {
      auto in = stream();
      for (Cell c : parse_cell_list(fixed, in, name)) EXPECT_TRUE(fixed.is_free(c));
    });
    succeeds_or_map_error("load_cell_list", [&] { load_cell_list(fixed, path); });
  }
  EXPECT_GE(parsed, 1);  // the seed maps in the directory parse
}
