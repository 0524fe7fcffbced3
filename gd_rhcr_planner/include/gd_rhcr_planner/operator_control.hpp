// The operator's controls over a running fleet: pause and resume the whole fleet or one robot,
// and an emergency stop. A held robot (paused, or any robot while the emergency stop is engaged)
// stays in its cell and keeps its task; paused robots get no new task and an unpicked task may
// move to another robot (Dispatcher). The node reports the state in the robots' modes
// (RobotState.MODE_PAUSED / MODE_STOPPED) and in rviz. ROS-free; tested in
// test/operator_test.cpp.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace gd_rhcr_planner {

// Same values as gd_rhcr_msgs/RobotState MODE_PAUSED and MODE_STOPPED (after RobotMode's 0..3).
enum OperatorMode : uint8_t { kModePaused = 4, kModeStopped = 5 };

class OperatorControl {
 public:
  explicit OperatorControl(int num_robots) : paused_(num_robots, 0) {}

  // robot -1 = the whole fleet (resuming the fleet also resumes robots paused one by one).
  // Returns "" when done, else why not (an unknown robot id).
  std::string set_paused(int64_t robot, bool paused);
  void set_emergency_stop(bool on) { estop_ = on; }

  bool emergency_stop() const { return estop_; }
  bool fleet_paused() const { return fleet_paused_; }
  bool paused(int r) const { return fleet_paused_ || paused_[r]; }
  bool holds(int r) const { return estop_ || paused(r); }
  int paused_count() const;
  bool any_held() const { return estop_ || paused_count() > 0; }
  // For Dispatcher::dispatch: 1 for robots that take no task now; empty when none is paused.
  std::vector<uint8_t> unavailable() const;
  // The mode a robot is commanded with: the emergency stop over pause over `mode` (its task's),
  // except that an offline robot stays offline (3).
  uint8_t mode(int r, uint8_t mode) const;
  // One line: "running", "fleet paused", "3 robots paused", "EMERGENCY STOP", ...
  std::string summary() const;

 private:
  std::vector<uint8_t> paused_;
  bool fleet_paused_ = false, estop_ = false;
};

}  // namespace gd_rhcr_planner
