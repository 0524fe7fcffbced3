// The per-tick execution layer of the planner node, ROS-free: robot liveness and consistency,
// planning, reservation, commitment and validation. Unit-tested in test/execution_test.cpp.
//
// An Action Dependency Graph as in Hönig, Kiesel, Tinka, Durham and Ayanian, "Persistent and
// Robust Execution of MAPF Schedules in Warehouses" (RA-L 2019), over a rolling horizon. Every
// tick the planner (GD-RHCR, its lazy group replans included) plans one more synchronous step
// from the robots' *committed end states*; the step is committed: each robot's new cell is
// appended to its committed path and to the cell's queue of visits, in plan order. A robot is
// commanded its next committed cell (the move is "dispatched") as soon as every robot that the
// plan sends through that cell earlier has left it (reported arrival in its next cell); robots do
// not move in lock-step: advance() does this between ticks too, as the arrival reports come in.
// A dispatched cell stays reserved for the robot until it reports arrival, and a commitment is
// never changed by a replan, so any pattern of delays gives no collision, and, since commitments
// follow one global plan order with cycles (rotations) turned into waits, no deadlock. Moves not
// dispatched yet may still be taken back: those queued behind a late robot are
// (revoke_behind_late). A robot with `commit_horizon` moves committed and not finished (the one
// it is making included) is immovable for the planner in that step (the others plan around it).
//
// Bad robots do not stop the fleet: a robot that never reported (missing) is left out once the
// caller allows it; a robot that is offline, silent, or inconsistent (a report of a cell another
// robot is in or entering, a jump, or a move nobody commanded) becomes an immovable obstacle at its
// last known cell, and every cell it may be entering is blocked; the other robots' undispatched
// commitments are then rebuilt (a "resync"), so nobody waits for a robot that will not move. An
// inconsistent robot is told to stay where it reports, and is believed once its report fits (a free
// neighbour). A slip (a report of a free neighbour) is believed, also into a cell another robot was
// sent into but has not left its own cell for: that robot's move is taken back. A robot that reports
// the cell it is entering (RobotRecord::entering) is caught while it slips: the cell it enters is
// kept clear from that report on, not only once it has arrived.
//
// The planner's agents are the placed robots, each under one agent index for the executor's
// lifetime, given when the robot is first placed (in robot id order: the identity when every
// robot reports before the first step). A placed robot stays an agent whatever becomes of it (a
// bad or late robot is an immovable agent), so the planner's per-agent state (PIBT priorities,
// GD-RHCR's cached plans) stays with its robot; a robot with no known cell yet is no agent
// (nothing can be planned for it) and joins with the next free index.
//
// Turning robots (issue 23). In the rotation action model (ExecutorConfig::action_model; LoRR's
// MAPF_T, gdrhcr/action_model.hpp) a robot's state is a pose, its cell and heading, and its
// commitments are poses: a move forward into the neighbour it faces (a visit of that cell, queued
// as above) or a quarter turn in place (no visit: the robot stays first in its own cell's queue,
// so the cell stays reserved for it while it turns, and is left only by a forward move). A turn
// is dispatched as soon as it is the robot's next commitment and is done when the robot reports
// the new heading at rest; a heading nobody commanded is believed (the robot is replanned from
// there). Every planned step is validated as rotation actions. In the mapf model headings are
// not planned; the commands still carry each move's heading, and a robot that reports a heading
// and waits for its next committed move is told to turn towards it in place meanwhile, so a
// turning robot loses no time on turns while it waits (what a real fleet's executor does).
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "gd_rhcr_planner/deadline_planner.hpp"
#include "gd_rhcr_planner/fleet.hpp"
#include "gdrhcr/action_model.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/validator.hpp"

namespace gd_rhcr_planner {

enum class RobotHealth : uint8_t { kOk, kMissing, kOffline, kSilent, kInconsistent };
const char* robot_health_name(RobotHealth h);

struct ExecutorConfig {
  int commit_horizon = 1;       // moves a robot may have committed and not finished, the one it makes included (>= 1)
  double plan_deadline_s = 0;   // per planner call (DeadlinePlanner); <= 0 waits for the planner
  size_t dist_budget_bytes = size_t(256) << 20;  // distance table around bad robots
  // A late robot's undispatched moves and those of the robots waiting to enter its cell are
  // taken back (transitively) and planned again around it, instead of queueing behind it.
  bool revoke_behind_late = true;
  // Catch-up: a robot that lost time (it was late at a tick, its commitments were taken back
  // behind a late robot, or it got no move in the tick's step) is owed a step per tick lost, up
  // to this many; after the tick's step it makes one more move along the planner's intended path
  // (Planner::intended_next) while it is owed steps and the cell is free (in the rotation model,
  // forward moves only). Robots whose moves take less than a tick so make up lost time at their
  // own speed (0 = off).
  int catch_up = 0;
  // The robots' action model: kMapf (moves to any neighbour) or kRotation (forward, quarter turns;
  // the planner and the distance table must plan in it too).
  gdrhcr::ActionModel action_model = gdrhcr::ActionModel::kMapf;
};

struct TickOutput {
  bool stepped = false;          // false: no command this tick (skip_reason says why)
  std::string skip_reason;
  std::vector<Cell> cells;       // per robot id: its cell as the executor knows it (kNoCell: missing)
  std::vector<Cell> command;     // per robot id: the cell to be in or head for (kNoCell: no command)
  std::vector<gdrhcr::Heading> command_heading;  // per robot id: the heading to face there (kNoHeading: any)
  std::vector<gdrhcr::Heading> headings;  // per robot id: its heading as the executor knows it (kNoHeading: none)
  std::vector<Cell> end_state;   // per robot id: the end of its commitments
  std::vector<RobotHealth> health;
  std::vector<int> robot_of_agent;  // planner agent index -> robot id (the placed robots; indices never change)
  std::vector<std::vector<Cell>> agent_goals;  // the goals the planner got, per agent
  bool planner_called = false;
  DeadlineOutcome outcome;       // of the planner call
  int held = 0;                  // planned moves turned into waits (immovable robots and robots behind them)
  int waiting = 0;               // robots whose next committed move waits for robots ahead of them
  int dispatched = 0;            // moves commanded for the first time this tick
  int resyncs = 0;               // commitments rebuilt this tick (a robot changed health, slipped)
  int revoked = 0;               // robots whose undispatched moves were taken back (revoke_behind_late)
  int caught_up = 0;             // extra moves committed to robots owed steps (ExecutorConfig::catch_up)
  std::string plan_error;        // the planned step was rejected by the validator: nobody got a new move
  std::vector<std::string> warnings;  // robots that changed health, unexpected reports
};

class Executor {
 public:
  // `dist` is the fleet's shared distance table (no robots blocked); grid and dist outlive this.
  Executor(const gdrhcr::Grid& grid, const gdrhcr::DistTable& dist, int num_robots, ExecutorConfig cfg);

  // One tick. robots: the fleet's records by id (Fleet::robot); goals: Fleet::fill_goals.
  // proceed_without_missing: robots that never reported are left out; when false, no step is made
  // while any robot is missing. The planner must have been built for at least num_robots agents.
  // hold (optional, per robot): robots that get no new move (paused, emergency stop); a move
  // already commanded is not taken back (the robot may be making it). The flags are read during
  // this call only (as are advance()'s): pass them again to hold the robots in the next call.
  TickOutput tick(const std::vector<RobotRecord>& robots, const std::vector<std::vector<Cell>>& goals,
                  DeadlinePlanner& planner, bool proceed_without_missing,
                  const std::vector<uint8_t>* hold = nullptr);

  // Between ticks: takes the robots' arrival reports (a robot at rest in the cell it was
  // commanded into) and dispatches the moves that this makes ready, at once rather than at the
  // next tick (a robot behind another enters its cell as soon as it has left). Any other report
  // (a slip, a change of health) waits for the next tick, and until then nobody is sent into a
  // cell such a report names (or that a robot moving without a command may be entering).
  // Returns the robots given a new move; command(r) is the cell to send each.
  std::vector<int> advance(const std::vector<RobotRecord>& robots, const std::vector<uint8_t>* hold = nullptr);
  // The cell robot r is commanded now: its dispatched cell, else its own cell. An inconsistent
  // robot is told to stay in the cell it reports (not sent on to a cell that may not be next to
  // it); one moving where the executor cannot tell gets no command (kNoCell).
  Cell command(int r) const;
  // The heading robot r is to face in command(r): a dispatched pose's, in the mapf model the
  // heading of its next committed move while it waits for it (it turns in place meanwhile), else
  // its own (kNoHeading when it reports none).
  gdrhcr::Heading command_heading(int r) const;
  // Every robot's cell as the executor has accepted it (kNoCell: not placed); a report it rejected
  // (inconsistent) is not in it. Fleet::set_accepted_cells takes it.
  std::vector<Cell> accepted_cells() const;

  const ExecutorConfig& config() const { return cfg_; }
  void set_plan_deadline(double s) { cfg_.plan_deadline_s = s; }
  int num_robots() const { return static_cast<int>(tracks_.size()); }
  // Introspection (tests, markers): robot r's committed cells not reached yet, in order (a turn
  // repeats its cell); the first is being made when dispatched(r). committed_poses: with headings.
  std::vector<Cell> committed(int r) const;
  std::vector<gdrhcr::Pose> committed_poses(int r) const;
  bool dispatched(int r) const { return tracks_[r].dispatched; }
  int agent_of(int r) const { return agent_of_robot_[r]; }  // robot r's planner agent index, -1 before it is placed
  Cell cell(int r) const { return tracks_[r].cell; }
  gdrhcr::Heading heading(int r) const { return tracks_[r].heading; }
  RobotHealth health(int r) const { return tracks_[r].health; }
  uint64_t steps() const { return steps_; }            // planned steps so far
  uint64_t resyncs_total() const { return resyncs_total_; }
  // Invariant check (tests): every robot's visits are queued in its path order and each
  // cell's queue starts with the robot in it, if any. Empty when fine, else what is wrong.
  std::string check_invariants() const;
  // The robots queued to visit cell c, with their state (debugging, tests).
  std::string debug_queue(Cell c) const;
  // The robots queued to visit cell c, in order (the first is in it or enters it next).
  std::vector<int> visitors(Cell c) const;

 private:
  struct Track {
    bool active = false;        // has a known cell and is planned (as a robot or an obstacle)
    RobotHealth health = RobotHealth::kMissing;
    Cell cell = gdrhcr::kNoCell;
    gdrhcr::Heading heading = gdrhcr::kNoHeading;  // rotation: planned; mapf: as reported
    std::deque<gdrhcr::Pose> path;  // committed poses after (cell, heading); mapf: each move's heading
    bool dispatched = false;    // path.front() was commanded: reserved until arrival (a turn: until done)
    uint64_t dispatched_at = 0; // the tick (counted by tick()) of that command
    Cell claimed = gdrhcr::kNoCell;  // inconsistent: the cell it reported (blocked)
    bool unknown_move = false;  // reported moving with no move commanded: its neighbours are blocked
    bool reported_moving = false;  // its last report said it is between two cells
    int owed = 0;               // catch_up: planned steps owed to it
    uint64_t stepped = 0;       // the planning step (steps_) that last gave it a new pose
    uint64_t revoked = 0;       // the tick that last took back its commitments
  };

  // The robots' reports against what the executor knows: placement, arrivals, slips, health.
  void reconcile(const std::vector<RobotRecord>& robots, TickOutput& out);
  bool place(int r, const RobotRecord& rec, TickOutput& out);
  bool fall_silent(int r, TickOutput& out);
  bool take_report(int r, const std::vector<RobotRecord>& robots, TickOutput& out);
  bool take_heading(int r, const RobotRecord& rec, TickOutput& out);
  RobotHealth report_health(int r, const RobotRecord& rec, TickOutput& out) const;
  bool rotation() const { return cfg_.action_model == gdrhcr::ActionModel::kRotation; }
  // Late: commanded a move in an earlier tick and not arrived yet.
  bool late(const Track& t) const { return t.dispatched && t.dispatched_at < ticks_; }
  bool take_unexpected_cell(int r, Cell x, const std::vector<RobotRecord>& robots, TickOutput& out);
  bool take_entering(int r, Cell x, const std::vector<RobotRecord>& robots, TickOutput& out);
  int yield_cell(int r, Cell x, const std::vector<RobotRecord>& robots, const char* how, TickOutput& out,
                 bool& withdrawn);
  bool withdraw_move(int q, Cell x, int r, const std::vector<RobotRecord>& robots);
  bool set_health(int r, RobotHealth h, TickOutput& out);
  void resync();
  void arrive(int r);
  int revoke(int r);
  int revoke_behind_late();
  // Dispatches every move whose cell's earlier visitors have left, except to robots on hold;
  // `sent` (optional) gets the robots.
  // `avoid` (optional, sorted): cells nobody is sent into now.
  int dispatch_ready(TickOutput& out, uint64_t stamp, const std::vector<uint8_t>& hold,
                     std::vector<int>* sent = nullptr, const std::vector<Cell>* avoid = nullptr);
  std::vector<Cell> unaccounted_cells(const std::vector<RobotRecord>& robots) const;
  int holder_of(Cell c, int except) const;
  void add_blocked_cells(int r, std::vector<Cell>& blocked) const;
  const gdrhcr::DistTable& dist_for(const std::vector<Cell>& obstacles);
  std::vector<Cell> planner_goals(int r, const std::vector<Cell>& fleet_goals, Cell end) const;
  // One planning step's input, per planner agent, and the cells to keep the agents out of.
  struct StepInput {
    std::vector<Cell> positions;     // committed end states (a bad robot: its cell)
    std::vector<gdrhcr::Heading> headings, next_headings;  // rotation: at the end states, planned
    std::vector<uint8_t> immovable;  // bad robots, robots with full commitments or on hold
    std::vector<Cell> obstacles;     // bad robots' cells (the distance table routes around them)
    std::vector<Cell> blocked;       // where bad robots may be besides (then the late cells too)
    std::vector<Cell> late_cells;    // cells of late robots and of robots waiting on a committed move
  };
  void plan_and_commit(const std::vector<std::vector<Cell>>& goals, const std::vector<uint8_t>& hold,
                       DeadlinePlanner& planner, TickOutput& out);
  void gather_agents(const std::vector<std::vector<Cell>>& goals, const std::vector<uint8_t>& hold, StepInput& in,
                     TickOutput& out) const;
  std::vector<Cell> call_planner(StepInput& in, DeadlinePlanner& planner, TickOutput& out);
  void commit_step(StepInput& in, std::vector<Cell>& next, TickOutput& out);
  void catch_up(const std::vector<std::vector<Cell>>& goals, const std::vector<uint8_t>& hold,
                const gdrhcr::Planner& planner, TickOutput& out);
  std::vector<uint8_t> owe_steps(const std::vector<uint8_t>& hold);

  const gdrhcr::Grid& grid_;
  const gdrhcr::DistTable& dist_;
  ExecutorConfig cfg_;
  std::vector<Track> tracks_;
  std::vector<int> robot_of_agent_, agent_of_robot_;  // planner agents: the placed robots, in the order placed
  std::unordered_map<Cell, std::deque<int>> visits_;  // robots that will be in a cell, in plan order
  gdrhcr::StepValidator validator_;
  std::vector<Cell> obstacle_cells_;  // the cells the current obstacle table blocks
  std::shared_ptr<const gdrhcr::DistTable> obstacle_dist_;
  uint64_t steps_ = 0, resyncs_total_ = 0, ticks_ = 0;
};

// Cycles of robots that would each enter the cell the next one leaves (rotations, and swaps) cannot
// be executed by robots that do not move in lock-step: their moves become waits (held set). Returns
// the number of robots put on hold.
int hold_rotations(const std::vector<Cell>& pos, std::vector<Cell>& next, std::vector<uint8_t>& held);

// What a robot known at `known` does to reach the commanded cell and heading: forward into
// another cell, a turn in place (a half turn starts clockwise), or a wait.
gdrhcr::Action command_action(gdrhcr::Pose known, Cell cell, gdrhcr::Heading heading);

}  // namespace gd_rhcr_planner
