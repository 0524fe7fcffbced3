// The planner node's health for diagnostic_updater: a level and message from the node's counters,
// judged against the previous update, so a problem shows while it happens (new overruns, rejected
// steps, deadline misses, task store errors since the last update; robots missing now) and the
// status clears when it stops. ROS-free; tested in test/operator_test.cpp.
#pragma once

#include <cstdint>
#include <string>

namespace gd_rhcr_planner {

struct HealthCounters {
  uint64_t overruns = 0, rejected_plans = 0, fallback_ticks = 0, store_errors = 0, skipped_ticks = 0;
  int missing_robots = 0, offline_robots = 0, paused_robots = 0;
  bool emergency_stop = false;
};

struct Health {
  uint8_t level = 0;  // diagnostic_msgs/DiagnosticStatus: OK 0, WARN 1, ERROR 2
  std::string message;
};

class HealthMonitor {
 public:
  Health update(const HealthCounters& now);

 private:
  HealthCounters last_;
  bool first_ = true;
};

}  // namespace gd_rhcr_planner
