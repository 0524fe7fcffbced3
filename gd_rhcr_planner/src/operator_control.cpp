#include "gd_rhcr_planner/operator_control.hpp"

namespace gd_rhcr_planner {

std::string OperatorControl::set_paused(int64_t robot, bool paused) {
  const int n = static_cast<int>(paused_.size());
  if (robot == -1) {
    fleet_paused_ = paused;
    if (!paused) paused_.assign(paused_.size(), 0);
    return "";
  }
  if (robot < 0 || robot >= n)
    return "unknown robot id " + std::to_string(robot) + " (fleet has " + std::to_string(n) +
           " robots; -1 = the whole fleet)";
  paused_[robot] = paused;
  return "";
}

int OperatorControl::paused_count() const {
  if (fleet_paused_) return static_cast<int>(paused_.size());
  int k = 0;
  for (uint8_t p : paused_) k += p;
  return k;
}

std::vector<uint8_t> OperatorControl::unavailable() const {
  if (paused_count() == 0) return {};
  std::vector<uint8_t> out(paused_.size());
  for (size_t r = 0; r < out.size(); ++r) out[r] = paused(static_cast<int>(r));
  return out;
}

uint8_t OperatorControl::mode(int r, uint8_t mode) const {
  if (mode == 3) return mode;  // offline
  if (estop_) return kModeStopped;
  if (paused(r)) return kModePaused;
  return mode;
}

std::string OperatorControl::summary() const {
  std::string s;
  if (estop_) s = "EMERGENCY STOP";
  if (fleet_paused_) s += std::string(s.empty() ? "" : ", ") + "fleet paused";
  else if (int k = paused_count()) s += std::string(s.empty() ? "" : ", ") + std::to_string(k) + " robots paused";
  return s.empty() ? "running" : s;
}

}  // namespace gd_rhcr_planner
