// Minimum-cost assignment (the Hungarian method with potentials, Kuhn 1955 / Munkres 1957, in
// the shortest-augmenting-path form of Jonker and Volgenant): every row of a rows x cols cost
// matrix gets its own column (or every column its own row when there are fewer columns), and the
// total cost is minimal. O(min^2 * max) time. Used by the batch dispatcher (dispatcher.hpp).
// ROS-free; tested against exhaustive search in test/dispatcher_test.cpp.
#pragma once

#include <cstdint>
#include <vector>

namespace gd_rhcr_planner {

// cost[r * cols + c]. Returns, for every row, its column, or -1 for rows left without one (only
// when rows > cols). Costs must be finite; keep them below about 2^52 in total.
std::vector<int> min_cost_assignment(const std::vector<int64_t>& cost, int rows, int cols);

}  // namespace gd_rhcr_planner
