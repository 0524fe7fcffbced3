#include "gdrhcr/lanes.hpp"

#include <algorithm>

namespace gdrhcr {

namespace {

// The open lines along one axis: `lines` lines of `len` cells, free(i, k) for cell k of line i;
// a line is open when at least half of its cells are free.
template <typename Free>
std::vector<char> open_lines(int lines, int len, Free free) {
  std::vector<char> open(lines, 0);
  for (int i = 0; i < lines; ++i) {
    int n = 0;
    for (int k = 0; k < len; ++k) n += free(i, k);
    open[i] = 2 * n >= len;
  }
  return open;
}

// Calls f(first, end) for each run [first, end) of open lines.
template <typename F>
void for_each_run(const std::vector<char>& open, F f) {
  const int lines = static_cast<int>(open.size());
  for (int i = 0; i < lines;) {
    if (!open[i]) {
      ++i;
      continue;
    }
    int j = i;
    while (j < lines && open[j]) ++j;
    f(i, j);
    i = j;
  }
}

// Lanes along one axis: each run of one open line is an aisle.
std::vector<Heading> lanes_along(const std::vector<char>& open, Heading first, Heading second) {
  std::vector<Heading> dir(open.size(), kNoHeading);
  int lane = 0;
  for_each_run(open, [&](int i, int j) {
    if (j - i == 1) dir[i] = lane++ % 2 ? second : first;
  });
  return dir;
}

// Open areas along one axis: the runs of two or more open lines beyond the first or the last
// aisle (between the aisles and the map's edge), if the axis has more aisles than lines in such
// runs. Runs between aisles are highways between shelf blocks; where wide runs outnumber the
// aisles they are the map's main travel space (the side rooms of warehouse-10-20-10-2-1).
std::vector<char> areas_along(const std::vector<char>& open) {
  std::vector<char> area(open.size(), 0);
  int aisles = 0, wide = 0, first = -1, last = -1;
  for_each_run(open, [&](int i, int j) {
    (j - i == 1 ? aisles : wide) += j - i;
    if (j - i == 1) last = i, first = first < 0 ? i : first;
  });
  if (aisles > wide)
    for_each_run(open, [&](int i, int j) {
      if (j - i > 1 && (j <= first || i > last)) std::fill(area.begin() + i, area.begin() + j, 1);
    });
  return area;
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

// Whether a cell is free, by line and position along it: rows (y, x) and columns (x, y).
auto row_free(const Grid& grid) {
  return [&grid](int y, int x) { return grid.is_free(grid.cell(x, y)); };
}
auto col_free(const Grid& grid) {
  return [&grid](int x, int y) { return grid.is_free(grid.cell(x, y)); };
}
std::vector<char> open_rows(const Grid& grid) { return open_lines(grid.height(), grid.width(), row_free(grid)); }
std::vector<char> open_cols(const Grid& grid) { return open_lines(grid.width(), grid.height(), col_free(grid)); }

}  // namespace

Lanes derive_lanes(const Grid& grid, LaneStyle style) {
  const int w = grid.width(), h = grid.height();
  Lanes l;
  if (style == LaneStyle::kLines) {
    l.row = lines_along(h, w, row_free(grid), kEast, kWest);
    l.col = lines_along(w, h, col_free(grid), kSouth, kNorth);
    return l;
  }
  l.row = lanes_along(open_rows(grid), kEast, kWest);
  l.col = lanes_along(open_cols(grid), kSouth, kNorth);
  return l;
}

OpenAreas derive_open_areas(const Grid& grid) { return {areas_along(open_rows(grid)), areas_along(open_cols(grid))}; }

bool OpenAreas::along(const Grid& grid, Cell c, Heading h) const {
  return h == kEast || h == kWest ? row[grid.y_of(c)] : col[grid.x_of(c)];
}

int OpenAreas::num_lines() const {
  return static_cast<int>(std::count(row.begin(), row.end(), 1) + std::count(col.begin(), col.end(), 1));
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
