// Task dispatch for the planner node. Two policies:
// * greedy (Fleet's rule before issue 14): queued tasks by priority then id, each to the nearest
//   idle robot; assignments are final;
// * batch: every tick, the queued tasks and the tasks assigned but not yet picked up are matched
//   to robots by minimum total travel to the pickups (an optimal assignment, assignment.hpp),
//   priority tier by priority tier (higher first). Robots count when idle, when holding a task
//   not yet picked (so a waiting task moves to a robot that is now nearer, if that saves more than
//   `switch_margin` cells), and when carrying a load at most `finish_horizon` cells from its
//   delivery (cost: cells to the delivery, then to the pickup): a task whose best robot is about
//   to finish waits for it instead of fetching a far idle robot. A task waiting in the queue gains
//   `age_weight` cells per tick, so a far task is not passed over for ever.
// ROS-free; tested in test/dispatcher_test.cpp.
#pragma once

#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "gd_rhcr_planner/fleet.hpp"
#include "gdrhcr/dist_table.hpp"

namespace gd_rhcr_planner {

enum class DispatchPolicy { kGreedy, kBatch };
// "greedy" or "batch"; throws gdrhcr::ParamError naming the value otherwise.
DispatchPolicy parse_dispatch_policy(const std::string& name);
const char* dispatch_policy_name(DispatchPolicy p);

struct DispatchParams {
  int finish_horizon = 10;   // a loaded robot this close to its delivery (cells) may be given the next task
  int switch_margin = 4;     // an unpicked task moves to another robot only if that saves more cells than this
  int max_tasks = 256;       // tasks per batch (highest priority, then lowest id); bounds the time per tick
  double age_weight = 0.05;  // cells of travel a tick of waiting in the queue is worth
  // Throws gdrhcr::ParamError naming a value out of range.
  void validate() const;
};

// What the batch solver sees of a robot and a task (built from Fleet by Dispatcher::dispatch).
struct DispatchRobot {
  int id = -1;
  Cell from = gdrhcr::kNoCell;  // where it is free: its cell, or the delivery of the load it carries
  int eta = 0;                  // cells until it is free (0 unless it carries a load)
  bool can_take_now() const { return eta == 0; }
};
struct DispatchTask {
  uint64_t id = 0;
  Cell pickup = gdrhcr::kNoCell;
  int priority = 0;
  int holder = -1;       // the robot it is assigned to (not picked), -1 when queued
  double waited = 0;     // ticks in the queue so far
};

struct DispatchStats {
  int robots = 0;        // robots in the batch (idle, holding an unpicked task, or about to finish)
  int tasks = 0;         // tasks in the batch
  int assigned = 0;      // queued tasks given to a robot this tick
  int reassigned = 0;    // unpicked tasks moved to another robot this tick
  int reserved = 0;      // tasks left waiting for a robot about to finish
  int64_t travel = 0;    // cells to the pickups of this tick's new assignments (and moves)
  double time_s = 0;     // wall time of the batch
};

// The batch decision: the robot that should hold each task whose holder changes (-1: queue).
struct BatchResult {
  std::vector<Fleet::Reassignment> changes;
  DispatchStats stats;
};
BatchResult solve_batch(const std::vector<DispatchRobot>& robots, const std::vector<DispatchTask>& tasks,
                        const gdrhcr::DistTable& dist, const DispatchParams& params);

class Dispatcher {
 public:
  Dispatcher(DispatchPolicy policy, DispatchParams params);
  DispatchPolicy policy() const { return policy_; }
  const DispatchParams& params() const { return params_; }
  void set_params(const DispatchParams& p) { p.validate(); params_ = p; }
  // Assigns tasks after Fleet::advance (which then only makes the transitions: this turns
  // Fleet's own greedy assignment off and applies the policy's). `unavailable[r]` (may be empty): robot r gets no task
  // now (paused by the operator) and its unpicked task may move to another robot.
  DispatchStats dispatch(Fleet& fleet, const gdrhcr::DistTable& dist, const std::vector<uint8_t>& unavailable);

 private:
  DispatchStats greedy(const std::vector<DispatchRobot>& robots, const std::vector<DispatchTask>& tasks,
                       const gdrhcr::DistTable& dist, Fleet& fleet) const;

  DispatchPolicy policy_;
  DispatchParams params_;
  uint64_t tick_ = 0;
  std::unordered_map<uint64_t, uint64_t> queued_since_;  // task -> tick it was first seen queued
};

}  // namespace gd_rhcr_planner
