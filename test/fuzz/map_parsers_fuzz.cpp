// libFuzzer targets for everything that reads map input. One source, built once per target with
// GDRHCR_FUZZ_MODE selecting the entry point (see CMakeLists.txt):
//   0 fuzz_movingai   Grid::parse_movingai
//   1 fuzz_kiva       Grid::parse_kiva
//   2 fuzz_map        Grid::parse (format detection), then the consumers of a parsed map:
//                     components, the MAPD rule, both task streams (goals must be free and in
//                     the agent's component)
//   3 fuzz_cell_list  parse_cell_list against a fixed small map
// A parser may succeed or throw MapError; any other exception, crash, hang or sanitizer report
// is a bug. Inputs that found one go to test/data/fuzz_regressions/ (replayed by
// test/core/fuzz_regressions_test.cpp).
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <string>

#include "gdrhcr/grid.hpp"
#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {

void check(bool ok) {
  if (!ok) __builtin_trap();
}

void exercise(const Grid& g) {
  size_t in_components = 0;
  for (int k = 0; k < g.count_components(); ++k) {
    check(!g.component_cells(k).empty());
    for (Cell c : g.component_cells(k)) check(g.is_free(c) && g.component(c) == k);
    in_components += g.component_cells(k).size();
  }
  check(in_components == g.free_cells().size());
  const Cell start = g.free_cells()[g.free_cells().size() / 2];
  RandomNavigationStream random(g, 7);
  Cell cur = start;
  for (int k = 0; k < 6; ++k) {
    const Cell next = random.next_goal(1, cur);
    check(g.is_free(next) && g.component(next) == g.component(start));
    check(next != cur || g.component_cells(g.component(cur)).size() == 1);
    cur = next;
  }
  MapdCells cells = default_mapd_cells(g);
  try {
    PickupDeliveryStream mapd(g, cells.pickups, cells.deliveries, 3);
    cur = start;
    for (int k = 0; k < 6; ++k) {
      const Cell next = mapd.next_goal(0, cur);
      check(g.component(next) == g.component(start));
      cur = next;
    }
  } catch (const std::invalid_argument&) {
    // Unreachable sets or a start without pickups: a documented, clear error.
  }
}

const Grid& fixed_grid() {
  static const Grid g = Grid::from_rows({"..@...", ".@@.e.", "......", "r@..@."}, "fixed");
  return g;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  std::istringstream in(std::string(reinterpret_cast<const char*>(data), size));
  try {
#if GDRHCR_FUZZ_MODE == 0
    Grid::parse_movingai(in, "fuzz.map");
#elif GDRHCR_FUZZ_MODE == 1
    Grid::parse_kiva(in, "fuzz.map");
#elif GDRHCR_FUZZ_MODE == 2
    exercise(Grid::parse(in, "fuzz.map"));
#else
    for (Cell c : parse_cell_list(fixed_grid(), in, "fuzz.cells")) check(fixed_grid().is_free(c));
#endif
  } catch (const MapError&) {
  }
  return 0;
}
