// A planner with a per-tick deadline: the primary planner (GD-RHCR, RHCR, ...) runs on its own
// worker thread; when it has not returned by the deadline, the fallback planner (PIBT, about a
// millisecond for a thousand robots) moves the fleet for that tick instead, so a slow solve never
// makes the node miss a tick. The late primary step is discarded. While the primary is still
// busy with an abandoned step, later ticks use the fallback at once. Planners are stateful but
// all of ours plan from the positions they are given, so skipping ticks only costs them a replan.
// ROS-free; unit-tested in test/deadline_planner_test.cpp.
#pragma once

#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "gdrhcr/planner.hpp"

namespace gd_rhcr_planner {

struct DeadlineOutcome {
  gdrhcr::StepReport report;
  bool fallback = false;      // the fallback planner moved the fleet this tick
  bool primary_late = false;  // ... because the primary missed this tick's deadline
  bool primary_busy = false;  // ... because the primary was still on an abandoned step
  std::string primary_error;  // ... because the primary threw (its message)
};

class DeadlinePlanner {
 public:
  DeadlinePlanner(std::unique_ptr<gdrhcr::Planner> primary, std::unique_ptr<gdrhcr::Planner> fallback);
  // Waits for an abandoned primary step to finish (bounded by the planner's own timeouts).
  ~DeadlinePlanner();
  DeadlinePlanner(const DeadlinePlanner&) = delete;
  DeadlinePlanner& operator=(const DeadlinePlanner&) = delete;

  // Fills next like Planner::plan_step. deadline_s <= 0 waits for the primary without limit.
  // The world's vectors are copied for the worker; `keep_alive` is held until the primary's
  // step ends, for what the world refers to that the caller may drop sooner (its DistTable).
  DeadlineOutcome step(const gdrhcr::WorldView& world, std::vector<gdrhcr::Cell>& next, double deadline_s,
                       std::shared_ptr<const void> keep_alive = nullptr);

  // The primary, for name/params/stats and introspection; only between steps, and only when
  // primary_idle() (a late step may still be running on the worker).
  const gdrhcr::Planner& primary() const { return *primary_; }
  bool primary_idle() const;
  // Blocks until an abandoned primary step has finished (tests, shutdown).
  void wait_idle();

 private:
  struct Job;
  void worker_loop();

  std::unique_ptr<gdrhcr::Planner> primary_, fallback_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::shared_ptr<Job> job_;  // the step the worker is on (or just finished), if any
  bool stop_ = false;
  std::thread worker_;
};

}  // namespace gd_rhcr_planner
