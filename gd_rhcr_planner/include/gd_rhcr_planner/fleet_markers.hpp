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

#include "gd_rhcr_planner/fleet_view.hpp"
#include "gd_rhcr_planner/map_loader.hpp"
#include "gdrhcr/grid.hpp"

namespace gd_rhcr_planner {

struct MarkerStyle {
  std::string frame_id = "map";
  int label_limit = 60;
  bool show_goal_lines = false;
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

 private:
  geometry_msgs::Point point(gdrhcr::Cell c, double z) const;
  visualization_msgs::Marker base(const std::string& ns, int type, int id = 0) const;
  void emit(std::vector<visualization_msgs::Marker>& all, visualization_msgs::Marker m) const;
  // The layers, each appended to `all`.
  void robots_layer(const FleetView& v, std::vector<visualization_msgs::Marker>& all);
  void groups_layer(const FleetView& v, std::vector<visualization_msgs::Marker>& all) const;
  void paths_layer(const FleetView& v, std::vector<visualization_msgs::Marker>& all) const;
  void goal_lines_layer(const FleetView& v, std::vector<visualization_msgs::Marker>& all) const;
  void tasks_layer(const FleetView& v, std::vector<visualization_msgs::Marker>& all) const;
  void operator_layer(const FleetView& v, std::vector<visualization_msgs::Marker>& all) const;
  void labels_layer(const FleetView& v, std::vector<visualization_msgs::Marker>& all) const;
  void overlay_layer(const FleetView& v, std::vector<visualization_msgs::Marker>& all) const;
  // The markers of `all` that differ from the last call's, and deletions of those gone.
  visualization_msgs::MarkerArray changes(std::vector<visualization_msgs::Marker>&& all);

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
