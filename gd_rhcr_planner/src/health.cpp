#include "gd_rhcr_planner/health.hpp"

#include <algorithm>

namespace gd_rhcr_planner {

Health HealthMonitor::update(const HealthCounters& now) {
  const HealthCounters before = first_ ? HealthCounters{} : last_;
  first_ = false;
  last_ = now;
  Health h;
  auto add = [&](uint8_t level, const std::string& what) {
    h.level = std::max(h.level, level);
    h.message += (h.message.empty() ? "" : "; ") + what;
  };
  auto grew = [](uint64_t a, uint64_t b) { return b > a ? std::to_string(b - a) : std::string(); };
  if (now.emergency_stop) add(1, "emergency stop engaged: all robots hold");
  if (now.missing_robots > 0) add(1, std::to_string(now.missing_robots) + " robots not reporting");
  if (auto d = grew(before.rejected_plans, now.rejected_plans); !d.empty()) add(2, d + " planned steps rejected; robots held");
  if (auto d = grew(before.store_errors, now.store_errors); !d.empty()) add(2, d + " task store write errors");
  if (auto d = grew(before.overruns, now.overruns); !d.empty()) add(1, d + " tick overruns");
  if (auto d = grew(before.fallback_ticks, now.fallback_ticks); !d.empty())
    add(1, d + " ticks past the plan deadline (PIBT moved the fleet)");
  if (auto d = grew(before.skipped_ticks, now.skipped_ticks); !d.empty() && now.missing_robots == 0)
    add(1, d + " ticks skipped (inconsistent robot states)");
  if (now.offline_robots > 0) add(0, std::to_string(now.offline_robots) + " robots offline");
  if (now.paused_robots > 0) add(0, std::to_string(now.paused_robots) + " robots paused");
  if (h.message.empty()) h.message = "planning";
  return h;
}

}  // namespace gd_rhcr_planner
