// The lifelong MAPF simulation loop: ask the planner for every agent's next cell, validate the
// step (a violation throws CollisionError), move, and hand a new goal to every agent that
// reached its goal. Throughput = goals reached / timesteps. In the rotation action model
// (action_model.hpp) every agent also carries a heading, the planner returns the next headings
// and every step is validated as actions of that model; a goal is reached on its cell, in any
// heading (as in LoRR).
#pragma once

#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/task_stream.hpp"

namespace gdrhcr {

struct SimOptions {
  int steps = 500;
  int lookahead = 3;          // goals known per agent: the current one and lookahead-1 more
  bool record_paths = false;
  // The action model in force; the DistTable given to run_simulation must be built in it.
  ActionModel action_model = ActionModel::kMapf;
  // Rotation: each agent's heading at the start; empty = all east (kEast), as in the Start-Kit.
  std::vector<Heading> start_headings;
  // > 0: no step after the first starts after this much wall time (SimResult::steps says how
  // many ran).
  double wall_limit_s = 0;
  bool free_flow = true;  // compute SimResult::free_flow_throughput (a distance row per goal)
};

// Where the steps of errands go: per errand, the steps from getting its goal to reaching it,
// split into forward moves (a change of cell), turns (rotation: the heading changes in place)
// and waits (neither). Summed over the errands reached.
struct ErrandSteps {
  long errands = 0;
  long forward = 0, turns = 0, waits = 0;
  long steps() const { return forward + turns + waits; }
  nlohmann::json to_json() const;  // the sums per errand
};

struct SimResult {
  int steps = 0;
  int agents = 0;
  long goals_reached = 0;
  double throughput = 0;
  double free_flow_throughput = 0;
  long collisions = 0;        // stays 0: a collision aborts the run with CollisionError
  int planned_steps = 0;      // steps in which the planner ran a solver
  double plan_time_mean_s = 0, plan_time_max_s = 0;
  double step_wall_mean_s = 0, step_wall_max_s = 0;  // wall time of plan_step, every step
  double step_wall_p99_s = 0;  // its 99th percentile (the least time 99% of the steps keep to)
  double step_cpu_mean_s = 0;  // process CPU time of plan_step (all threads), per step
  double wall_time_s = 0;
  // Progress: a goal is late once the agent has spent more than twice the shortest distance
  // from where it got the goal (at least 2 steps) without reaching it. Dense runs must not
  // livelock: these show agents that starve.
  long agents_late = 0;      // agents that had at least one late goal
  long goals_late = 0;       // goals (reached or not) that became late
  long late_at_end = 0;      // agents whose current goal is late when the run ends
  int longest_wait = 0;      // most consecutive steps an agent stood still off its goal
  double max_lateness = 0;   // largest (steps taken or elapsed) / shortest distance of a goal
  // The errands reached, and the same agents' errands in free flow (each alone on shortest
  // paths, as free_flow_throughput: no waits). Their difference per errand says where a run
  // loses its throughput: longer ways (forward), more turns, or waits.
  ErrandSteps errand_steps, free_flow_errand_steps;
  // Goals reached (errands) in each block of kTimelineSteps steps, the last block possibly short:
  // shows where a long run loses its throughput.
  static constexpr int kTimelineSteps = 100;
  std::vector<long> goals_timeline;
  ActionModel action_model = ActionModel::kMapf;
  std::vector<std::vector<Cell>> paths;  // paths[agent][t], when recorded
  std::vector<std::vector<Heading>> headings;  // headings[agent][t], when recorded in rotation
  nlohmann::json to_json() const;        // the figures above (not the paths)
};

SimResult run_simulation(const Grid& grid, const DistTable& dist, TaskStream& tasks,
                         Planner& planner, const std::vector<Cell>& starts,
                         const SimOptions& options);

// Goals per timestep if every agent followed the same goal sequence alone on shortest paths:
// the physical upper bound a planner is compared against. With a rotation DistTable the paths
// are over (cell, heading) states, so turns count: each agent starts with start_headings (empty
// or null: east) and arrives at each goal with the heading of its shortest path (forward
// preferred over a turn among equally short actions). Step costs (lanes, traffic) do not count:
// the paths are the shortest in steps.
double free_flow_throughput(const Grid& grid, const DistTable& dist, const TaskStream& tasks,
                            const std::vector<Cell>& starts, int steps,
                            const std::vector<Heading>* start_headings = nullptr,
                            ErrandSteps* errand_steps = nullptr);  // the free-flow errands' steps

}  // namespace gdrhcr
