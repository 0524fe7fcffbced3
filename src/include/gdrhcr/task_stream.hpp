// Seeded task streams for lifelong MAPF: each agent draws its goals from its own random
// generator, so an agent's goal sequence depends only on (seed, agent id), never on the planner
// or on timing. That makes runs reproducible and lets the free-flow bound replay the same goals.
#pragma once

#include <cstdint>
#include <istream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "gdrhcr/grid.hpp"

namespace gdrhcr {

// splitmix64: decorrelates (seed, stream id) pairs into generator seeds.
uint64_t mix_seed(uint64_t seed, uint64_t stream);

class TaskStream {
 public:
  virtual ~TaskStream() = default;
  virtual std::string name() const = 0;
  // The next goal of `agent`, who stands at `current` (the goal always differs from it when the
  // map allows, and is always reachable from it). Called in order for each agent; agents are
  // independent. Throws std::invalid_argument when `current` is not a free cell.
  virtual Cell next_goal(int agent, Cell current) = 0;
  // Whether `goal`, just returned by next_goal(agent, from), is an errand: counted when reached.
  // By default a goal equal to `from` is not (an agent alone in a one-cell region gets its own
  // cell). TaskListStream says otherwise (see there).
  virtual bool is_errand(int agent, Cell goal, Cell from) const {
    (void)agent;
    return goal != from;
  }
  // A fresh stream with the same seed and rules, at the start of every agent's sequence.
  virtual std::unique_ptr<TaskStream> clone_fresh() const = 0;
};

// Each new goal is a uniformly random free cell of the current cell's 4-connected component
// (other than the current cell), so goals are always reachable; on a connected map that is any
// free cell. An agent alone in a one-cell component gets its own cell as goal, forever.
class RandomNavigationStream : public TaskStream {
 public:
  RandomNavigationStream(const Grid& grid, uint64_t seed);
  std::string name() const override { return "random"; }
  Cell next_goal(int agent, Cell current) override;
  std::unique_ptr<TaskStream> clone_fresh() const override;

 private:
  std::mt19937_64& rng(int agent);
  const Grid& grid_;
  uint64_t seed_;
  std::vector<std::mt19937_64> rngs_;
};

// Multi-agent pickup and delivery: agents alternate pickup, delivery, pickup, ... each drawn
// uniformly from the cells of its set in the agent's 4-connected component. See
// `default_mapd_cells` for how the sets are chosen for a map.
//
// Reachability rule: the constructor rejects (std::invalid_argument naming the cell) sets where
// a pickup cannot reach any delivery or a delivery cannot reach any pickup; so once an agent has
// a goal it never runs out of reachable goals. An agent that starts in a component without
// pickups cannot be given a task: next_goal throws std::invalid_argument naming the agent and
// its cell (the simulator asks for every agent's first goals before the first step).
class PickupDeliveryStream : public TaskStream {
 public:
  PickupDeliveryStream(const Grid& grid, std::vector<Cell> pickups, std::vector<Cell> deliveries,
                       uint64_t seed);
  std::string name() const override { return "mapd"; }
  Cell next_goal(int agent, Cell current) override;
  std::unique_ptr<TaskStream> clone_fresh() const override;
  const std::vector<Cell>& pickups() const { return pickups_; }
  const std::vector<Cell>& deliveries() const { return deliveries_; }

 private:
  const Grid& grid_;
  std::vector<Cell> pickups_, deliveries_;
  // The sets split by component (in the given order), indexed by Grid::component.
  std::vector<std::vector<Cell>> pickups_by_component_, deliveries_by_component_;
  uint64_t seed_;
  std::vector<std::mt19937_64> rngs_;
  std::vector<uint8_t> next_is_delivery_;
};

// A fixed task list run in order, as the League of Robot Runners (LoRR) Start-Kit v1.1.5 does
// (src/CompetitionSystem.cpp and src/driver.cpp; the problem JSON's "taskAssignmentStrategy"),
// for a team of `team_size` agents and m tasks:
//  - RoundRobin ("roundrobin", InfAssignSystem): agent k's j-th task is tasks[(j * team_size + k)
//    % m]; the list repeats forever. Task ids count assignments in order (the Start-Kit's
//    task_id: the simulator assigns agents in id order, as the Start-Kit's update_tasks does).
//  - RoundRobinFixed ("roundrobin_fixed", FixedAssignSystem): task i goes to agent i % team_size,
//    once; ids are agent-major (agent 0's tasks first). Then none.
//  - Greedy ("greedy", TaskAssignSystem): one shared queue; the next task goes to whichever
//    agent asks next (in the simulator, agents in id order each step), each task once; its id
//    is its place in the list.
// As in the Start-Kit, every task is an errand: one on the agent's own cell, or equal to its
// previous one (length zero), is finished by standing on it after a step and counts; a task the
// agent cannot reach (another 4-connected region) is assigned all the same and holds the agent
// for good. An agent without a task (list exhausted) gets its own cell as goal, which is no
// errand, and id -1. assigned_ids(agent) lists the ids handed to the agent so far, in order.
class TaskListStream : public TaskStream {
 public:
  enum class Strategy { RoundRobin, RoundRobinFixed, Greedy };
  // Throws std::invalid_argument for an empty list, a task off the map or on an obstacle, or
  // team_size < 1.
  TaskListStream(const Grid& grid, std::vector<Cell> tasks, int team_size, Strategy strategy);
  std::string name() const override { return "lorr-tasks"; }
  Cell next_goal(int agent, Cell current) override;
  bool is_errand(int agent, Cell goal, Cell from) const override;
  std::unique_ptr<TaskStream> clone_fresh() const override;
  const std::vector<Cell>& tasks() const { return tasks_; }
  Strategy strategy() const { return strategy_; }
  const std::vector<long>& assigned_ids(int agent) const;
  // "roundrobin", "roundrobin_fixed", "greedy"; parse_strategy throws std::invalid_argument.
  static const char* to_string(Strategy s);
  static Strategy parse_strategy(const std::string& s);

 private:
  const Grid& grid_;
  std::vector<Cell> tasks_;
  int team_size_;
  Strategy strategy_;
  long next_shared_ = 0;                 // Greedy: next queue position
  long next_id_ = 0;                     // RoundRobin: assignments so far
  std::vector<long> next_round_;         // RoundRobin*: per agent, tasks drawn so far (j)
  std::vector<long> fixed_first_id_;     // RoundRobinFixed: per agent, the id of its first task
  std::vector<std::vector<long>> ids_;   // per agent, ids handed out
};

// Throws std::invalid_argument unless both sets are non-empty, every cell is free, every pickup
// can reach some delivery and every delivery some pickup; the message names the first bad cell.
void check_mapd_cells(const Grid& grid, const std::vector<Cell>& pickups,
                      const std::vector<Cell>& deliveries);

struct MapdCells {
  std::vector<Cell> pickups, deliveries;
  std::string rule;  // how they were chosen, recorded in results
};

// The documented rule for pickup and delivery cells:
//  - kiva maps: pickups are the endpoints `e` (shelf access), deliveries the homes `r`
//    (the workstation columns on the left and right);
//  - other maps: deliveries are the free cells of the leftmost and rightmost free columns
//    (the stations of the MovingAI warehouse maps), pickups are the other free cells with an
//    obstacle 4-neighbour inside the map (the cells in front of shelves). Where a set would be
//    empty, it falls back to all free cells.
// On a map with several components, cells of either set that cannot reach the other set are
// dropped (and `rule` says how many), so the result passes check_mapd_cells when any component
// holds both kinds.
MapdCells default_mapd_cells(const Grid& grid);

// The MAPD cells for a map file: side files `<map without .map>.pickups` and `.deliveries`
// beside it when both exist (the generated sortation maps have them), else the rule above.
MapdCells mapd_cells_for_map(const Grid& grid, const std::string& map_path);

// Reads a list of cells, one "x y" (or "x,y") per line, '#' comments allowed. Throws MapError
// naming the line for a malformed entry, a cell off the map or on an obstacle.
std::vector<Cell> load_cell_list(const Grid& grid, const std::string& path);
// The same on a stream; `name` is used in messages.
std::vector<Cell> parse_cell_list(const Grid& grid, std::istream& in, const std::string& name);

// `count` distinct free cells drawn with `seed`. Throws std::invalid_argument when the map has
// fewer free cells than agents.
std::vector<Cell> random_starts(const Grid& grid, int count, uint64_t seed);

}  // namespace gdrhcr
