// The ROS-free bookkeeping of the planner node: tasks (queued -> assigned -> picked ->
// delivered, or failed/cancelled), the robots' latest reported cells, nearest-idle-robot
// assignment by the core's DistTable, each robot's goal sequence for the planner's WorldView,
// and the safety cascade that holds robots in place behind robots that cannot move.
// Unit-tested without a ROS master (test/fleet_test.cpp).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/grid.hpp"

namespace gd_rhcr_planner {

using gdrhcr::Cell;

// Same values as gd_rhcr_msgs/TaskStatus and RobotState.
enum TaskState : uint8_t { kQueued = 0, kAssigned = 1, kPicked = 2, kDelivered = 3, kFailed = 4, kCancelled = 5 };
enum RobotMode : uint8_t { kIdle = 0, kToPickup = 1, kToDelivery = 2, kOffline = 3 };
const char* task_state_name(uint8_t s);
inline bool task_finished(uint8_t s) { return s == kDelivered || s == kFailed || s == kCancelled; }

struct TaskRecord {
  uint64_t id = 0;
  int pickup_x = 0, pickup_y = 0, delivery_x = 0, delivery_y = 0;
  Cell pickup = gdrhcr::kNoCell, delivery = gdrhcr::kNoCell;
  int priority = 0;
  uint8_t state = kQueued;
  int robot = -1;
  std::string reason;
};

struct TaskEvent {  // one status transition, to publish on task_status
  uint64_t task_id;
  uint8_t state;
  int robot;
  std::string reason;
};

struct SubmitResult {
  bool accepted = false;
  uint64_t task_id = 0;
  std::string reason;
};

struct RobotRecord {
  bool reported = false;
  Cell cell = gdrhcr::kNoCell;
  bool offline = false;           // reported_offline || silent || stuck: an obstacle, gets no task
  bool reported_offline = false;  // the robot's own report (mode OFFLINE)
  bool stuck = false;             // its reports have not fitted for too long (Fleet::set_stuck)
  bool silent = false;            // no report for longer than the offline timeout
  bool moving = false;
  Cell entering = gdrhcr::kNoCell;  // while moving: the cell it reports entering (kNoCell: not known)
  gdrhcr::Heading heading = gdrhcr::kNoHeading;  // the heading it reports (kNoHeading: none)
  double last_report = 0;         // time of the last accepted report (caller's clock, s)
  int64_t task = -1;
};

class Fleet {
 public:
  Fleet(const gdrhcr::Grid& grid, const gdrhcr::DistTable& dist, int num_robots);

  int num_robots() const { return static_cast<int>(robots_.size()); }
  // Validates and queues a task (requested_id 0 = a fresh id). A rejected task is kept as
  // FAILED with the reason (so ListTasks shows it) and a FAILED event is emitted.
  SubmitResult submit(int pickup_x, int pickup_y, int delivery_x, int delivery_y, int priority,
                      uint64_t requested_id = 0);
  bool cancel(uint64_t task_id, std::string& reason);
  // A robot's report at time `now` (seconds, any clock the caller also passes to mark_silent).
  // Returns false with `error` set for an unknown id or a cell that is off the map or blocked;
  // the report is then ignored. A report brings a silent robot back.
  // `entering` (optional, while moving): the cell the robot reports entering; it must be a free
  // neighbour of (x, y). `heading`: the one it reports (action_model.hpp), kNoHeading for none.
  bool update_robot(int64_t id, int x, int y, bool offline, bool moving, std::string& error,
                    double now = 0, std::optional<std::pair<int, int>> entering = std::nullopt,
                    gdrhcr::Heading heading = gdrhcr::kNoHeading);
  // Robots that have reported before but not within `timeout` seconds of `now` become silent:
  // offline (an obstacle at their last cell) until they report again; advance() then requeues
  // their tasks. Returns the robots that became silent in this call.
  std::vector<int> mark_silent(double now, double timeout);
  // A robot whose reports the execution layer has not believed for too long (it claims a cell
  // another robot holds, or one it cannot have reached) is taken out like an offline one: its task
  // is requeued by advance() and it gets none until it is cleared (stuck = false).
  void set_stuck(int r, bool stuck);
  int offline_count() const;
  bool all_reported() const;
  int missing_robots() const;
  // Robots on the same cell (a report error); empty when the positions are consistent.
  std::string position_conflict() const;

  // Status transitions from the robots' cells (picked, delivered; tasks of robots that went
  // offline are requeued, also picked ones: the load on a dead robot is fetched again from the
  // pickup; an assigned task whose pickup an offline robot stands on goes back to the queue),
  // then greedy assignment of queued tasks to the nearest idle robots. Tasks whose pickup or
  // delivery an offline robot stands on wait in the queue until it leaves.
  void advance();
  // The robots' cells as the execution layer accepted them (Executor::accepted_cells): a pickup or
  // delivery is counted only when the robot reports its cell and the execution layer accepted it
  // there (a report it rejected, a robot claiming another's cell or a jump, counts nothing).
  // Until this is called, every report counts.
  void set_accepted_cells(std::vector<Cell> cells);
  // Assignment by an outside dispatcher (dispatcher.hpp): with auto-assign off, advance() makes
  // the transitions only and leaves queued tasks to apply_assignments().
  void set_auto_assign(bool on) { auto_assign_ = on; }
  bool auto_assign() const { return auto_assign_; }
  struct Reassignment {
    uint64_t task;
    int robot;  // -1: back to the queue
  };
  // Applies a batch at once: each listed task (queued, or assigned and not picked) leaves its
  // robot, then goes to `robot` (online, and holding no task after the batch) or to the queue,
  // with one event each. Entries that do not fit are skipped; returns their reasons.
  std::vector<std::string> apply_assignments(const std::vector<Reassignment>& batch);
  // Goal sequences for the WorldView: to-pickup robots [pickup, delivery], to-delivery robots
  // [delivery], idle and offline robots [their cell].
  void fill_goals(std::vector<std::vector<Cell>>& goals) const;
  void fill_positions(std::vector<Cell>& positions) const;
  // The robot's state as the fleet sees it: kOffline for an offline or silent robot, else its
  // task's phase (kIdle, kToPickup, kToDelivery).
  uint8_t mode(int robot) const;
  // The mode a step command gives the robot: its task's phase, never kOffline. Offline is what a
  // robot reports, not an order: a robot that adopts the commanded mode (fleet_sim does) and was
  // told "offline" while it was silent would report offline forever and never come back.
  uint8_t command_mode(int robot) const;
  int64_t task_of(int robot) const { return robots_[robot].task; }
  const RobotRecord& robot(int r) const { return robots_[r]; }

  std::vector<TaskEvent> take_events();
  const TaskRecord* task(uint64_t id) const;
  const std::map<uint64_t, TaskRecord>& tasks() const { return tasks_; }
  // Cells still to travel for an active task (-1 when unknown or finished).
  int distance_left(uint64_t id) const;

  size_t count_in_state(uint8_t s) const;
  // Unfinished tasks, for the task store.
  std::vector<TaskRecord> open_tasks() const;
  // Re-creates tasks from the task store after a restart (before any report). Each task is
  // validated against the map again (a task whose cells are no longer valid fails with the
  // reason); assigned and picked tasks go back to their robot when it exists and holds no other
  // task, else to the queue. Returns the number of tasks restored as open.
  size_t restore(const std::vector<TaskRecord>& open, uint64_t delivered, uint64_t failed,
                 uint64_t next_id);
  uint64_t next_id() const { return next_id_; }
  uint64_t delivered_total() const { return delivered_; }
  uint64_t failed_total() const { return failed_; }
  // Finished tasks beyond this many are forgotten (oldest first).
  void set_finished_limit(size_t n) { finished_limit_ = n; }

 private:
  void set_state(TaskRecord& t, uint8_t s, int robot, const std::string& reason);
  bool validate_cell(int x, int y, const char* what, Cell& out, std::string& reason) const;
  void forget_old_finished();
  bool at_cell(int r, Cell c) const;  // robot r reports c, and the execution layer accepted it there

  const gdrhcr::Grid& grid_;
  const gdrhcr::DistTable& dist_;
  std::vector<RobotRecord> robots_;
  std::vector<Cell> accepted_;  // set_accepted_cells; empty: every report counts
  std::map<uint64_t, TaskRecord> tasks_;
  std::vector<uint64_t> finished_order_;
  std::vector<TaskEvent> events_;
  uint64_t next_id_ = 1;
  uint64_t delivered_ = 0, failed_ = 0;
  size_t finished_limit_ = 10000;
  bool auto_assign_ = true;
};

// The safety cascade: robots with held[i] set stay where they are, and so does every robot
// whose planned next cell is in `blocked` (cells a silent robot may be moving into); then every
// robot whose planned next cell is the current cell of a held robot is held too, until nothing
// changes. Holding only replaces moves by waits, so a valid plan stays free of swaps, and
// afterwards no robot enters a cell whose occupant may not leave. Returns the number held.
int hold_cascade(const gdrhcr::Grid& grid, const std::vector<Cell>& pos, std::vector<Cell>& next,
                 std::vector<uint8_t>& held, const std::vector<Cell>& blocked = {});

}  // namespace gd_rhcr_planner
