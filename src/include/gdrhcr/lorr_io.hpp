// League of Robot Runners (LoRR) instances in and out.
//
// In: a LoRR Start-Kit problem (2023 format; MAPF-Competition/Start-Kit, tag 2023-archive,
// "Input Output Format.md" and src/driver.cpp): a JSON object with
//   "mapFile", "agentFile", "taskFile"  paths relative to the problem file's folder,
//   "teamSize"                          number of agents (the first teamSize of the agent file),
//   "numTasksReveal" (default 1)        tasks known ahead per agent (our lookahead),
//   "taskAssignmentStrategy" (default "roundrobin"; also "roundrobin_fixed", "greedy").
// The map is MovingAI format (LoRR: `@` and `T` block, `.`, `E`, `S` are free; our Grid reads
// them so). Agent and task files: a first line with the count n, then n lines of one linear
// cell id each, id = row * width + col; blank lines and lines starting with '#' are skipped.
//
// Out: our run as a LoRR-style output JSON in the no-rotation model, the format LoRR's PlanViz
// replays (MAPF-Competition/PlanViz, commit c03a1d6, script/plan_config.py PlanConfig2023):
//   "actionModel" "MAPF", "AllValid" "Yes", "teamSize", "start" [[row, col, "N/A"], ...],
//   "numTaskFinished", "makespan" (timesteps simulated), "actualPaths" (one string per agent,
//   moves separated by commas), "errors" [] (a collision aborts our runs), "events" (per agent,
//   [[task id, timestep, "assigned" | "finished"], ...]), "tasks" [[id, row, col], ...].
// Move letters (PlanViz script/util.py state_transition_mapf and plan_config.py
// transition_state): "R" col + 1 (east), "L" col - 1 (west), "U" row + 1 ("south (down)": rows
// grow downwards, so U moves DOWN the map as drawn), "D" row - 1 (north, up the map), "W" wait.
// PlanViz's tracker_transfer.py swaps U and D when it converts MAPF-tracker paths, confirming
// that its U is row + 1.
#pragma once

#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/task_stream.hpp"

namespace gdrhcr {

// Every malformed or unusable LoRR file; the message names the file and the line or field.
class LorrError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct LorrProblem {
  std::string problem_path, map_path, agent_path, task_path;  // resolved paths
  Grid grid;
  int team_size = 0;
  int num_tasks_reveal = 1;
  TaskListStream::Strategy strategy = TaskListStream::Strategy::RoundRobin;
  std::vector<Cell> starts;  // team_size cells, distinct
  std::vector<Cell> tasks;
};

// A valid step of our MAPF planners (pos -> next, Planner::plan_step) as actions of the rotation
// model (action_model.hpp, LoRR's MAPF_T), kept valid conservatively: an agent facing its next cell moves forward; one not facing it turns
// towards it and stays; an agent whose next cell is the cell of an agent that stays, stays too
// (transitively, so no vertex conflict appears). The MAPF step has no swaps, so the result has
// none. A half turn starts clockwise.
std::vector<Action> rotation_actions_for_step(const Grid& grid, const std::vector<Cell>& pos,
                                              const std::vector<Heading>& headings, const std::vector<Cell>& next);

// Reads the problem JSON and the files it names. Throws LorrError (or MapError for the map).
LorrProblem load_lorr_problem(const std::string& problem_path);
// One agent or task file: the count line, then that many cell ids on `grid`.
std::vector<Cell> load_lorr_cells(const Grid& grid, const std::string& path, const std::string& what);

// Records every goal a TaskStream hands out, per agent, so a run can be written as LoRR output
// (goal cells and, for a TaskListStream, the task ids). clone_fresh() gives the inner stream's
// fresh clone, unrecorded.
class RecordingTaskStream : public TaskStream {
 public:
  explicit RecordingTaskStream(TaskStream& inner) : inner_(inner) {}
  std::string name() const override { return inner_.name(); }
  Cell next_goal(int agent, Cell current) override;
  std::unique_ptr<TaskStream> clone_fresh() const override { return inner_.clone_fresh(); }
  const std::vector<std::vector<Cell>>& goals() const { return goals_; }
  TaskStream& inner() { return inner_; }

 private:
  TaskStream& inner_;
  std::vector<std::vector<Cell>> goals_;
};

// The LoRR output of a run: paths[i][t] = agent i's cell at time t (t = 0..steps), the goals
// each agent was handed in order (RecordingTaskStream::goals), the lookahead the simulator used,
// and task ids per agent (TaskListStream::assigned_ids; empty = number the tasks ourselves).
// Events are rebuilt with the simulator's rule: the first `lookahead` goals are assigned at
// t = 0; when an agent stands on its current goal at time t it is finished at t and the next
// goal is assigned at t. A goal equal to the cell it was drawn from (no task) is not reported.
nlohmann::json lorr_output(const Grid& grid, const std::vector<std::vector<Cell>>& paths,
                           const std::vector<std::vector<Cell>>& goals, int lookahead,
                           const std::vector<std::vector<long>>& task_ids = {});

// The executed paths of a LoRR output JSON (start + actualPaths replayed with the letters
// above), checked against the grid: a bad letter, a move off the map or into an obstacle is a
// LorrError naming `name`, the agent and the move. paths[i][t] as above.
std::vector<std::vector<Cell>> read_lorr_paths(const Grid& grid, const nlohmann::json& output,
                                               const std::string& name);

}  // namespace gdrhcr
