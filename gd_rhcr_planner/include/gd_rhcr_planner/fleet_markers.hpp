// The rviz picture of the fleet, one marker namespace per layer so each can be toggled:
//   robots       oriented triangles (heading of the last move), coloured by planner group
//                (GD-RHCR's groups; one colour per robot for planners without groups), grey offline
//   groups       links between the members of each group of two or more robots
//   paths        each robot's planned path along the aisles (the planner's window; the next step
//                when the planner keeps no path, e.g. PIBT)
//   goal_lines   straight robot-to-goal lines, only with show_goal_lines
//   stations     all pickup (orange) and delivery (green) stations of the map, faint
//   tasks        pickup and delivery cells of the open tasks
//   operator     paused robots framed yellow; a red frame around the map on emergency stop
//   labels       robot ids, for fleets up to label_limit robots
//   overlay      a text block above the map: tick, deliveries per minute, open tasks, groups, plan time
// update() returns only the markers that differ from what it returned before (stamps are zero,
// frame_locked off), so an unchanged layer is not re-sent. Uses message types only (no node, no
// master); tested in test/operator_test.cpp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <visualization_msgs/MarkerArray.h>

#include "gd_rhcr_planner/map_loader.hpp"
#include "gdrhcr/grid.hpp"

namespace gd_rhcr_planner {

struct MarkerStyle {
  std::string frame_id = "map";
  int label_limit = 60;
  bool show_goal_lines = false;
};

// One tick of the fleet as the markers show it (vectors indexed by robot id).
struct FleetView {
  std::vector<gdrhcr::Cell> pos, next;
  std::vector<gdrhcr::Cell> goal;                // first goal (kNoCell or own cell: none)
  std::vector<int> group_of;                     // group index per robot
  std::vector<uint8_t> offline, held;            // held: paused or emergency stop
  std::vector<std::vector<gdrhcr::Cell>> paths;  // planned paths (may be empty)
  std::vector<gdrhcr::Cell> task_pickups, task_deliveries;  // of the open tasks
  bool emergency_stop = false;
  std::string overlay;                           // the text block
};

class FleetMarkers {
 public:
  FleetMarkers(const gdrhcr::Grid& grid, const MapFrame& frame, MarkerStyle style);
  // The stations layer (static; call once, publish latched with the rest).
  void set_stations(const std::vector<gdrhcr::Cell>& pickups, const std::vector<gdrhcr::Cell>& deliveries);
  // All layers for `view`; only the markers that changed since the last call (all on the first).
  visualization_msgs::MarkerArray update(const FleetView& view);
  // Every marker as last built (a late subscriber's full picture).
  const std::vector<visualization_msgs::Marker>& current() const { return last_; }
  const MarkerStyle& style() const { return style_; }

  // Overlay text from the figures.
  static std::string overlay_text(uint64_t tick, double deliveries_per_min, size_t open, size_t queued,
                                  int groups, double plan_time_s, const std::string& planner,
                                  const std::string& dispatcher, const std::string& operator_state);

 private:
  geometry_msgs::Point point(gdrhcr::Cell c, double z) const;
  visualization_msgs::Marker base(const std::string& ns, int type, int id = 0) const;
  void emit(std::vector<visualization_msgs::Marker>& all, visualization_msgs::Marker m) const;

  const gdrhcr::Grid& grid_;
  MapFrame frame_;
  MarkerStyle style_;
  std::vector<double> heading_;  // per robot, radians (REP 103: 0 = +x)
  std::vector<visualization_msgs::Marker> stations_;
  std::vector<visualization_msgs::Marker> last_;
  std::vector<std::vector<uint8_t>> last_bytes_;
};

// A colour per index, spread around the hue circle (golden-ratio steps).
std_msgs::ColorRGBA group_colour(int i, float alpha = 1.0f);

}  // namespace gd_rhcr_planner
