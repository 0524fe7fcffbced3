// A step's wall-clock budget (GD-RHCR's step_budget): the primary solves get its first 60%, the
// guidance's refinement passes stop at 50% (the motion forecast's rollout follows them), the
// guidance searches stop at 85%, PIBT stops planning agents at 95% (the others step ahead or
// wait: with 10,000 agents on warehouse_large one PIBT step with turns takes 5-6 ms here);
// the final check and the bookkeeping follow. No budget: every deadline is open. A hard limit
// (WorldView::step_limit_s, less what the step does after PIBT) adds `limit`: PIBT stops there
// even when it began past its own deadline.
#pragma once

#include <chrono>

namespace gdrhcr {

struct StepBudget {
  using Clock = std::chrono::steady_clock;
  static constexpr double kSolveShare = 0.6;
  static constexpr double kRefineShare = 0.5;
  static constexpr double kGuidanceShare = 0.85;
  static constexpr double kSecondaryShare = 0.95;

  StepBudget() = default;
  StepBudget(Clock::time_point start, double seconds, double limit_s = 0) {
    if (seconds <= 0 && limit_s <= 0) return;
    this->start = start;
    if (limit_s > 0) limit = start + share(limit_s);
    if (seconds <= 0) return;
    solves = start + share(kSolveShare * seconds);
    refine = start + share(kRefineShare * seconds);
    guidance = start + share(kGuidanceShare * seconds);
    secondary = start + share(kSecondaryShare * seconds);
  }
  Clock::time_point solves = Clock::time_point::max();
  Clock::time_point refine = Clock::time_point::max();  // the guidance's refinement passes stop here
  Clock::time_point guidance = Clock::time_point::max();
  Clock::time_point secondary = Clock::time_point::max();  // PIBT stops planning agents here
  Clock::time_point start = Clock::time_point::max();      // the step's start (with a budget or a limit)
  Clock::time_point limit = Clock::time_point::max();      // PIBT stops here whatever (with a limit)

 private:
  static Clock::duration share(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }
};

}  // namespace gdrhcr
