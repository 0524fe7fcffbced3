// One-way lanes derived from a map's structure (issue 24, congestion in the rotation model).
//
// Warehouses are grids of one-cell aisles between shelves. Two robots that meet head-on in such
// an aisle cannot pass: one must turn round (two turns) and back out, and the robots behind it
// too. The League's winners send traffic one way along each aisle, alternating from one aisle to
// the next, like the streets of a city grid (WPPL's hand-made guidance graphs for the warehouse
// maps, Jiang et al., arXiv 2404.16162; Zhang et al., "Guidance Graph Optimization for Lifelong
// MAPF", IJCAI 2024). Here the aisles are found from the map, never from its name:
//   - a row (column) is open when at least half of its cells are free;
//   - a run of open rows one row high, between rows that are not open (shelves), is an aisle:
//     a one-way lane. Successive lanes alternate: east, west, east, ... (columns: south, north);
//   - wider runs of open rows are open areas (a depot, a random map, a room), and get no
//     direction: there robots pass each other without turning round.
// Style kLines makes every row and column one can travel along a lane instead (at least half of
// the moves along it between free cells), alternating in order among those lines (a crisscross,
// like WPPL's weights for its city and random maps). It organises open areas too, which the
// aisle rule leaves two-way. With guidance it loses where there are no aisles, but a fleet of
// thousands moved by PIBT over the distances alone gains with it (rule lanes,
// planner_params.cpp).
// A lane gives a direction only; DistTable makes a forward move against it dearer (lane-cost),
// so distances, and every planner that follows them, prefer the lane's way but may still take
// a short way back (it is a cost, not a rule, and never needed for a valid plan).
// Open areas: on an axis whose aisles outnumber its open lines in runs of two or more, the runs
// beyond its first or last aisle are open areas, such as the band between a warehouse's shelves
// and its stations at the map's edge (runs between aisles are highways). Travel along
// the map's length can keep to the aisles; an open area is where robots cross into an aisle or
// wait at a station, and travel along it crosses all of them. DistTable can make a forward move
// along an open area dearer (open-cost). An axis without aisles (a random map, a city) has none,
// nor one whose open runs are its main travel space (the side rooms of warehouse-10-20-10-2-1).
#pragma once

#include <vector>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/grid.hpp"

namespace gdrhcr {

struct Lanes {
  std::vector<Heading> row;  // per row: kEast or kWest for a lane, kNoHeading otherwise
  std::vector<Heading> col;  // per column: kSouth or kNorth for a lane, kNoHeading otherwise

  // True when a forward move in heading h into cell c goes against its row's or column's lane.
  bool against(const Grid& grid, Cell c, Heading h) const;
  int num_lanes() const;
};

enum class LaneStyle { kAisles, kLines };

struct OpenAreas {
  std::vector<char> row;  // per row: 1 when it is in an open area (on an axis with aisles)
  std::vector<char> col;  // per column: the same

  // True when a forward move in heading h into cell c goes along its row's or column's open area.
  bool along(const Grid& grid, Cell c, Heading h) const;
  int num_lines() const;
};

OpenAreas derive_open_areas(const Grid& grid);

Lanes derive_lanes(const Grid& grid, LaneStyle style = LaneStyle::kAisles);

}  // namespace gdrhcr
