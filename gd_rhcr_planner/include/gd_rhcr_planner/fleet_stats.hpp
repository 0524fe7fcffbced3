// Figures of a running fleet for gd_rhcr_msgs/PlannerStats fields and the rviz overlay:
// the planner's own counters read from its stats() JSON (0 when a planner does not report one),
// and deliveries per minute over a sliding window. ROS-free; tested in test/operator_test.cpp.
#pragma once

#include <cstdint>
#include <deque>
#include <utility>

#include <nlohmann/json.hpp>

namespace gd_rhcr_planner {

struct PlannerFigures {
  uint64_t solver_calls = 0;      // RHCR: PBS calls; GD-RHCR: primary (group) solves
  uint64_t solver_failures = 0;   // RHCR: failed PBS calls; GD-RHCR: failure fallbacks
  uint64_t solver_timeouts = 0;
  uint64_t pbs_nodes = 0;
  double solver_time_mean = 0;    // s per solver call
  double groups_mean_count = 0;   // GD-RHCR, per step so far
  double groups_mean_size = 0;
  double groups_replanned_per_step = 0;
  uint64_t cache_reuses = 0;
  uint64_t threshold_fallbacks = 0;
  uint64_t failure_fallbacks = 0;
  uint64_t repairs = 0;
  uint64_t pibt_swaps = 0;
};
PlannerFigures planner_figures(const nlohmann::json& stats);

// Deliveries per minute over the last `window_s` seconds (fewer at the start: over the time seen).
class ThroughputMeter {
 public:
  explicit ThroughputMeter(double window_s = 60.0) : window_(window_s) {}
  // `delivered`: the running total at time `now` (s, any monotonic clock).
  void add(double now, uint64_t delivered);
  double per_minute() const;

 private:
  double window_;
  std::deque<std::pair<double, uint64_t>> samples_;
};

}  // namespace gd_rhcr_planner
