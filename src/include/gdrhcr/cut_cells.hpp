// Cut cells: free cells whose removal disconnects their component (articulation points of the
// 4-connected grid graph, Tarjan's low-link algorithm, iterative). A map without them is
// biconnected: every two cells are joined by two paths that share no cell, so agents can always
// pass each other. Maps with dead ends and narrow passages (random-32-32-20, rooms) have them;
// warehouses and open maps usually do not.
#pragma once

#include <cstdint>
#include <vector>

#include "gdrhcr/grid.hpp"

namespace gdrhcr {

// Per cell: 1 for a cut cell, 0 otherwise (obstacles are 0).
std::vector<uint8_t> cut_cells(const Grid& grid);
// The share of free cells that are cut cells.
double cut_cell_share(const Grid& grid);

}  // namespace gdrhcr
