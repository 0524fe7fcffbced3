#include "gdrhcr/lanes.hpp"

namespace gdrhcr {

namespace {

// Lanes along one axis: `lines` lines of `len` cells, free(i, k) for cell k of line i.
template <typename Free>
std::vector<Heading> lanes_along(int lines, int len, Free free, Heading first, Heading second) {
  std::vector<char> open(lines, 0);
  for (int i = 0; i < lines; ++i) {
    int n = 0;
    for (int k = 0; k < len; ++k) n += free(i, k);
    open[i] = 2 * n >= len;
  }
  std::vector<Heading> dir(lines, kNoHeading);
  int lane = 0;
  for (int i = 0; i < lines;) {
    if (!open[i]) {
      ++i;
      continue;
    }
    int j = i;
    while (j < lines && open[j]) ++j;
    if (j - i == 1) dir[i] = lane++ % 2 ? second : first;
    i = j;
  }
  return dir;
}

}  // namespace

Lanes derive_lanes(const Grid& grid, LaneStyle style) {
  const int w = grid.width(), h = grid.height();
  Lanes l;
  if (style == LaneStyle::kLines) {
    for (int y = 0; y < h; ++y) l.row.push_back(y % 2 ? kWest : kEast);
    for (int x = 0; x < w; ++x) l.col.push_back(x % 2 ? kNorth : kSouth);
    return l;
  }
  l.row = lanes_along(h, w, [&](int y, int x) { return grid.is_free(grid.cell(x, y)); }, kEast, kWest);
  l.col = lanes_along(w, h, [&](int x, int y) { return grid.is_free(grid.cell(x, y)); }, kSouth, kNorth);
  return l;
}

bool Lanes::against(const Grid& grid, Cell c, Heading h) const {
  const Heading lane = h == kEast || h == kWest ? row[grid.y_of(c)] : col[grid.x_of(c)];
  return lane != kNoHeading && lane != h;
}

int Lanes::num_lanes() const {
  int n = 0;
  for (Heading d : row) n += d != kNoHeading;
  for (Heading d : col) n += d != kNoHeading;
  return n;
}

}  // namespace gdrhcr
