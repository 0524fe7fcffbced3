#include "gdrhcr/cut_cells.hpp"

#include <algorithm>

namespace gdrhcr {

std::vector<uint8_t> cut_cells(const Grid& grid) {
  const int n = grid.num_cells();
  std::vector<uint8_t> cut(n, 0);
  std::vector<int> disc(n, -1), low(n, 0);
  struct Frame {
    Cell u, parent;
    int next;  // index of the next neighbour to visit
  };
  std::vector<Frame> stack;
  int clock = 0;
  for (Cell root : grid.free_cells()) {
    if (disc[root] >= 0) continue;
    disc[root] = low[root] = clock++;
    int root_children = 0;
    stack.push_back({root, kNoCell, 0});
    while (!stack.empty()) {
      Frame& f = stack.back();
      const auto nb = grid.neighbours(f.u);
      if (f.next < nb.size()) {
        const Cell v = nb.begin()[f.next++];
        if (disc[v] < 0) {
          disc[v] = low[v] = clock++;
          if (f.u == root) ++root_children;
          stack.push_back({v, f.u, 0});
        } else if (v != f.parent) {
          low[f.u] = std::min(low[f.u], disc[v]);
        }
        continue;
      }
      const Cell u = f.u, parent = f.parent;
      stack.pop_back();
      if (parent == kNoCell) continue;
      low[parent] = std::min(low[parent], low[u]);
      if (parent != root && low[u] >= disc[parent]) cut[parent] = 1;
    }
    if (root_children > 1) cut[root] = 1;
  }
  return cut;
}

double cut_cell_share(const Grid& grid) {
  const auto cut = cut_cells(grid);
  const long count = std::count(cut.begin(), cut.end(), uint8_t{1});
  return grid.free_cells().empty() ? 0.0 : double(count) / grid.free_cells().size();
}

}  // namespace gdrhcr
