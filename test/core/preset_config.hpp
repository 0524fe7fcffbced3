// GD-RHCR's configuration of a preset as the parameter table gives it (planner_params.cpp), for
// tests that build GdRhcrPlanner directly: resolved on an open map (no cut cells) of a fleet below
// the thousands, with K_threshold left to the planner's own agent count.
#pragma once

#include <string>

#include "gdrhcr/gd_rhcr.hpp"
#include "gdrhcr/planner_params.hpp"

namespace gdrhcr {

inline GdRhcrConfig preset_config(const std::string& preset) {
  static const Grid open = Grid::from_rows({"....", "....", "....", "...."});
  Params p;
  p.set("preset", preset);
  GdRhcrConfig c = gd_rhcr_config(PlannerParams::resolve("gd-rhcr", p, MapFacts(open, 10)), 1);  // a fleet that leaves room (rule crowded-fleet)
  c.k_threshold = 0;  // the paper's rule for the planner's agent count
  return c;
}

}  // namespace gdrhcr
