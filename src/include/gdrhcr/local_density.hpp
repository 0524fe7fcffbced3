// Local density: the share of free cells that hold an agent in a box of the map, in O(1) per
// query from 2-D prefix sums counted once per step. GD-RHCR's density rule sends a group in a
// crowded neighbourhood to the secondary solver whatever its size (gd_rhcr.hpp, max_density).
#pragma once

#include <array>
#include <vector>

#include "gdrhcr/grid.hpp"

namespace gdrhcr {

class LocalDensity {
 public:
  explicit LocalDensity(const Grid& grid) : grid_(grid) {}
  // Counts the free cells and the agents standing at `positions`.
  void count(const std::vector<Cell>& positions);
  // Agents per free cell in the box {x0, y0, x1, y1} grown by `margin` cells (clipped to the
  // map); 1 when that holds no free cell.
  double around(const std::array<int, 4>& box, int margin) const;

 private:
  const Grid& grid_;
  std::vector<int> free_sum_, agent_sum_;  // (W+1) x (H+1) prefix sums
};

}  // namespace gdrhcr
