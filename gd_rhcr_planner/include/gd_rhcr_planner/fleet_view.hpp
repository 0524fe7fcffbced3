// One tick of the fleet as rviz shows it, in plain data (vectors indexed by robot id): built by
// the fleet manager (fleet_manager.hpp), drawn by FleetMarkers (fleet_markers.hpp).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/grid.hpp"

namespace gd_rhcr_planner {

struct FleetView {
  std::vector<gdrhcr::Cell> pos, next;
  std::vector<gdrhcr::Heading> heading;          // per robot (kNoHeading: none reported)
  std::vector<gdrhcr::Cell> goal;                // first goal (kNoCell or own cell: none)
  std::vector<int> group_of;                     // group index per robot
  std::vector<uint8_t> offline, held;            // held: paused or emergency stop
  std::vector<std::vector<gdrhcr::Cell>> paths;  // planned paths (may be empty)
  std::vector<gdrhcr::Cell> task_pickups, task_deliveries;  // of the open tasks
  bool emergency_stop = false;
  std::string overlay;                           // the text block (overlay_text)
};

// The overlay's text from the fleet's figures.
std::string overlay_text(uint64_t tick, double deliveries_per_min, size_t open, size_t queued, int groups,
                         double plan_time_s, const std::string& planner, const std::string& dispatcher,
                         const std::string& operator_state);

}  // namespace gd_rhcr_planner
