#include "gd_rhcr_planner/assignment.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace gd_rhcr_planner {

namespace {

// n <= m; a(i, j) for i < n, j < m. Returns the column of every row.
template <class Cost>
std::vector<int> solve(int n, int m, Cost a) {
  const int64_t inf = std::numeric_limits<int64_t>::max() / 4;
  // 1-based arrays, column 0 is the virtual start of each augmenting path.
  std::vector<int64_t> u(n + 1, 0), v(m + 1, 0), minv(m + 1);
  std::vector<int> p(m + 1, 0), way(m + 1, 0);
  std::vector<char> used(m + 1);
  for (int i = 1; i <= n; ++i) {
    p[0] = i;
    int j0 = 0;
    std::fill(minv.begin(), minv.end(), inf);
    std::fill(used.begin(), used.end(), 0);
    do {  // Dijkstra over reduced costs until a free column is reached
      used[j0] = 1;
      const int i0 = p[j0];
      int64_t delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const int64_t cur = a(i0 - 1, j - 1) - u[i0] - v[j];
        if (cur < minv[j]) minv[j] = cur, way[j] = j0;
        if (minv[j] < delta) delta = minv[j], j1 = j;
      }
      for (int j = 0; j <= m; ++j) {
        if (used[j]) u[p[j]] += delta, v[j] -= delta;
        else minv[j] -= delta;
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {  // flip the augmenting path
      const int j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0);
  }
  std::vector<int> col_of_row(n, -1);
  for (int j = 1; j <= m; ++j)
    if (p[j]) col_of_row[p[j] - 1] = j - 1;
  return col_of_row;
}

}  // namespace

std::vector<int> min_cost_assignment(const std::vector<int64_t>& cost, int rows, int cols) {
  if (rows < 0 || cols < 0 || cost.size() != static_cast<size_t>(rows) * cols)
    throw std::invalid_argument("min_cost_assignment: cost matrix size does not match rows x cols");
  if (rows == 0 || cols == 0) return std::vector<int>(rows, -1);
  if (rows <= cols)
    return solve(rows, cols, [&](int r, int c) { return cost[static_cast<size_t>(r) * cols + c]; });
  // More rows than columns: assign every column a row on the transposed matrix.
  const auto row_of_col =
      solve(cols, rows, [&](int c, int r) { return cost[static_cast<size_t>(r) * cols + c]; });
  std::vector<int> out(rows, -1);
  for (int c = 0; c < cols; ++c) out[row_of_col[c]] = c;
  return out;
}

}  // namespace gd_rhcr_planner
