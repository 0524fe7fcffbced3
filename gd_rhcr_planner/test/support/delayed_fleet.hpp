// Simulated robots for the execution layer (execution.hpp), ROS-free: robots that start a
// commanded move at once (no safety interlock), move at different speeds, occupy both cells while
// moving, and pause for random delays as in the League of Robot Runners 2026 (a delay starts on a
// tick with probability p_delay and lasts a uniform 1..D ticks; a robot at rest does not start its
// move, a moving robot stops where it is). Used by execution_test.cpp (any delay pattern: no
// collision, no deadlock) and bench/delay_benchmark.cpp (throughput with and without delays).
// fleet_sim (the ROS simulator) models the same robots over topics. Turning robots (issue 23,
// give_headings): each robot reports a heading and moves only forward; told a neighbour it does
// not face (the mapf model) it first turns towards it, a quarter turn taking as long as a move. Test and benchmark support
// (library gd_rhcr_fleet_testing), not part of the node.
#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "gd_rhcr_planner/execution.hpp"
#include "gdrhcr/action_model.hpp"
#include "gdrhcr/grid.hpp"

namespace gd_rhcr_planner {

struct SimRobot {
  static constexpr int kSub = 10;  // substeps per tick
  gdrhcr::Cell cell = gdrhcr::kNoCell, dst = gdrhcr::kNoCell;
  bool moving = false;
  int left = 0;         // substeps of the current move still to go
  int speed = kSub;     // substeps per move
  int delay = 0;        // substeps of delay left
  bool missing = false, silent = false, offline = false;
  gdrhcr::Cell fake = gdrhcr::kNoCell;  // reports this cell instead of its own (an inconsistent report)
  gdrhcr::Cell goal = gdrhcr::kNoCell;
  gdrhcr::Cell cmd = gdrhcr::kNoCell;  // the last command (a robot at rest starts it when it can)
  gdrhcr::Heading heading = gdrhcr::kNoHeading;      // turning robots: the heading it faces
  gdrhcr::Heading cmd_heading = gdrhcr::kNoHeading;  // ... and the last command's
  int turning = 0;      // +1 / -1 while a quarter turn clockwise / counter-clockwise is under way
  int turns = 0, turns_before_moves = 0;  // quarter turns made; those a command to a neighbour not faced made
  int goals_reached = 0;
  int moves = 0;
};

class DelayedFleet {
 public:
  // n robots on distinct random free cells, each with a random goal and a speed drawn uniformly
  // from [min_speed, max_speed] substeps per move (SimRobot::kSub substeps make a tick).
  DelayedFleet(const gdrhcr::Grid& g, int n, uint64_t seed, int min_speed = 3, int max_speed = 14);

  std::vector<SimRobot>& robots() { return robots_; }
  // What the robots report (Fleet::robot's records): missing robots report nothing.
  std::vector<RobotRecord> records() const;
  // Goals for Executor::tick; a robot at rest on its goal counts a goal reached (added to
  // `reached`) and gets a new random one. A goal under a robot that will not move is replaced
  // (as the fleet requeues tasks under offline robots).
  std::vector<std::vector<gdrhcr::Cell>> goals(int& reached);
  // Turning robots from now on: each gets a random heading (seeded), reports it, and turns (a
  // quarter turn taking its move time) towards a commanded neighbour before it moves forward.
  // forward_only: a command into a neighbour the robot does not face is a bad command (the
  // rotation model's commands turn robots first).
  void give_headings(bool forward_only);
  // Commands sent between ticks, given the robots' reports after a substep (Executor::advance,
  // Executor::command and command_heading).
  struct Command {
    int robot;
    gdrhcr::Cell cell;
    gdrhcr::Heading heading;
  };
  using Between = std::function<std::vector<Command>(const std::vector<RobotRecord>&)>;
  // Applies the commands and runs one tick of motion with delays (p_delay per robot and tick,
  // 1..max_delay_ticks ticks); a robot at rest starts its commanded move whenever it is not
  // delayed. With `between`, the robots' reports go to it after every substep and the commands it
  // returns are taken at once. Returns "" or what went wrong: a bad command (a moving robot told
  // another cell, a move to a non-neighbour) or two robots in one cell (collision_cell says where).
  std::string execute(const TickOutput& out, double p_delay, int max_delay_ticks, const Between& between = {});
  // Robots delayed right now.
  int delayed() const;
  // Robot i, off the floor so far (missing), is put on it: at its cell when no robot is in it, is
  // entering it or was commanded into it, else at the first free cell of the map no robot is.
  void join(size_t i);

  gdrhcr::Cell collision_cell = gdrhcr::kNoCell;
  // Ticks of the delay process per tick of execute (a planning step): with 3, a step stands for
  // three League ticks (moves of 3 ticks when a move takes the whole step): a delay starts with
  // probability 1 - (1 - p_delay)^3 per step and its 1..max_delay_ticks ticks last a third as many
  // steps each (at least one substep). 1: the delay process runs per step.
  int ticks_per_step = 1;

  // Dispatch on arrival, as the node's dispatch timer does: the robots' reports go to ex.advance
  // and the moves it frees are sent at once.
  static Between on_arrival(Executor& ex);

 private:
  gdrhcr::Cell random_cell(size_t robot);
  std::string take_command(size_t i, gdrhcr::Cell c, gdrhcr::Heading h);
  bool start_turn(SimRobot& s);
  void start_moves();
  std::string check_physical();

  const gdrhcr::Grid& g_;
  std::mt19937_64 rng_, delay_rng_;     // placement and speeds; delays
  std::vector<std::mt19937_64> goal_rng_;  // per robot: its goals
  std::vector<SimRobot> robots_;
  bool forward_only_ = false;
};

}  // namespace gd_rhcr_planner
