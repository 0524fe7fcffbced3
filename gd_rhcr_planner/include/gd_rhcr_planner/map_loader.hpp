// Maps for the planner node: a map_server YAML + PGM occupancy grid, or a MovingAI / RHCR kiva
// map read by the core (gdrhcr::Grid::load), with the metric frame that places it in `map`.
//
// Grid cells keep the core's convention: x = column, y = row counted from the TOP of the file
// (image or text). In the `map` frame (REP 103: metres, x right, y up) the top row is the one
// with the largest y, exactly as map_server publishes an image:
//   world_x = origin_x + (x + 0.5) * resolution
//   world_y = origin_y + (height - 1 - y + 0.5) * resolution
// and nav_msgs/OccupancyGrid row r (row 0 at the origin, at the bottom) is grid row height-1-r.
#pragma once

#include <string>
#include <vector>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/grid.hpp"

namespace gd_rhcr_planner {

struct MapFrame {
  double resolution = 1.0;  // metres per cell
  double origin_x = 0, origin_y = 0, origin_yaw = 0;  // pose of the lower-left corner of the map
  int height = 0;

  double world_x(int x) const { return origin_x + (x + 0.5) * resolution; }
  double world_y(int y) const { return origin_y + (height - 1 - y + 0.5) * resolution; }
  // Nearest cell of a point (may be off the map; check with Grid::in_bounds).
  int cell_x(double wx) const;
  int cell_y(double wy) const;
};

// The yaw in the map frame of a robot facing heading h (action_model.hpp): REP 103, counter-
// clockwise from +x. East (+x in cells and metres) is 0, north (-row in cells, +y in metres) pi/2,
// south -pi/2, west pi (map origins are not rotated, see load_map).
inline double heading_yaw(gdrhcr::Heading h) {
  constexpr double kYaw[gdrhcr::kNumHeadings] = {0.0, -1.5707963267948966, 3.141592653589793, 1.5707963267948966};
  return kYaw[h & 3];
}

struct LoadedMap {
  gdrhcr::Grid grid;
  MapFrame frame;
  std::string path;
  std::string format;  // "map_server", "movingai" or "kiva"
};

// Reads the map at `path`: `.yaml`/`.yml` as a map_server description (image PGM P2/P5, resolution,
// origin, negate, occupied_thresh, free_thresh; unknown cells count as obstacles), anything else
// with gdrhcr::Grid::load and `cell_size` metres per cell at origin (0, 0).
// Throws gdrhcr::MapError naming the file for any problem.
LoadedMap load_map(const std::string& path, double cell_size);

// A PGM image as grey values, row-major from the top row. Throws gdrhcr::MapError.
struct PgmImage {
  int width = 0, height = 0, maxval = 255;
  std::vector<int> pixels;
};
PgmImage read_pgm(const std::string& path);

// map_server's rule: occupancy p = (maxval - v) / maxval (or v / maxval with negate);
// p > occupied_thresh -> obstacle, p < free_thresh -> free, otherwise unknown (obstacle here).
gdrhcr::Grid grid_from_pgm(const PgmImage& img, bool negate, double occupied_thresh,
                           double free_thresh, const std::string& name);

}  // namespace gd_rhcr_planner
