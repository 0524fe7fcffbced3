// The overlay text of the fleet view (fleet_view.hpp).
#include "gd_rhcr_planner/fleet_view.hpp"

#include <cstdio>

namespace gd_rhcr_planner {

std::string overlay_text(uint64_t tick, double per_min, size_t open, size_t queued, int groups, double plan_time_s,
                         const std::string& planner, const std::string& dispatcher, const std::string& operator_state) {
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "tick %llu   %.1f deliveries/min   open tasks %zu (%zu queued)   groups %d   plan %.1f ms\n"
                "planner %s   dispatcher %s   %s",
                static_cast<unsigned long long>(tick), per_min, open, queued, groups, plan_time_s * 1e3,
                planner.c_str(), dispatcher.c_str(), operator_state.c_str());
  return buf;
}

}  // namespace gd_rhcr_planner
