// Shared by the Fleet and TaskStore tests: a small map and a robot report helper.
#pragma once

#include <string>

#include "gd_rhcr_planner/fleet.hpp"

namespace gd_rhcr_planner::fixtures {

// Two corridors joined at both ends around a row of obstacles.
inline gdrhcr::Grid corridor() {
  return gdrhcr::Grid::from_rows({
      "..........",
      ".@@@@@@@@.",
      "..........",
  });
}

// A robot's report; returns Fleet's error ("" when accepted).
inline std::string report(Fleet& f, int id, int x, int y, bool offline = false) {
  std::string err;
  f.update_robot(id, x, y, offline, false, err);
  return err;
}

}  // namespace gd_rhcr_planner::fixtures
