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

// kLines along one axis: a line is a lane when at least half of the moves along it (pairs of
// neighbouring cells) are between free cells; lanes alternate in order among those lines, so a
// map whose obstacles fall on every other line still gets both directions.
template <typename Free>
std::vector<Heading> lines_along(int lines, int len, Free free, Heading first, Heading second) {
  std::vector<Heading> dir(lines, kNoHeading);
  int lane = 0;
  for (int i = 0; i < lines; ++i) {
    int moves = 0;
    for (int k = 0; k + 1 < len; ++k) moves += free(i, k) && free(i, k + 1);
    if (2 * moves >= len - 1) dir[i] = lane++ % 2 ? second : first;
  }
  return dir;
}

}  // namespace

Lanes derive_lanes(const Grid& grid, LaneStyle style) {
  const int w = grid.width(), h = grid.height();
  Lanes l;
  auto row_free = [&](int y, int x) { return grid.is_free(grid.cell(x, y)); };
  auto col_free = [&](int x, int y) { return grid.is_free(grid.cell(x, y)); };
  if (style == LaneStyle::kLines) {
    l.row = lines_along(h, w, row_free, kEast, kWest);
    l.col = lines_along(w, h, col_free, kSouth, kNorth);
    return l;
  }
  l.row = lanes_along(h, w, row_free, kEast, kWest);
  l.col = lanes_along(w, h, col_free, kSouth, kNorth);
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
