// League of Robot Runners (LoRR) instances in and out.
//
// In: a LoRR Start-Kit problem (2023 format; MAPF-Competition/Start-Kit, tag 2023-archive,
// "Input Output Format.md" and src/driver.cpp): a JSON object with
//   "mapFile", "agentFile", "taskFile"  paths relative to the problem file's folder,
//   "teamSize"                          number of agents (the first teamSize of the agent file),
//   "numTasksReveal" (default 1)        tasks known ahead per agent (our lookahead),
//   "taskAssignmentStrategy" (default "roundrobin"; also "roundrobin_fixed", "greedy").
// The map is read as the Start-Kit reads it (load_lorr_map: only `@` and `T` block). Agent and task files: a first line with the count n, then n lines of one linear
// cell id each, id = row * width + col; blank lines and lines starting with '#' are skipped.
//
// Out: our run as the Start-Kit's output JSON (src/CompetitionSystem.cpp saveResults), which
// LoRR's PlanViz replays (MAPF-Competition/PlanViz, script/plan_config.py):
//   "actionModel" "MAPF_T" (rotation) or "MAPF", "AllValid" "Yes", "teamSize",
//   "start" [[row, col, orientation], ...] (E/S/W/N in MAPF_T, "N/A" in MAPF),
//   "numTaskFinished", "sumOfCost" and "makespan" (the Start-Kit's: timesteps in which an agent
//   had a task, summed and the largest), "actualPaths" and "plannerPaths" (one string per agent,
//   actions separated by commas; the same, as we execute what we plan), "errors" [] (a
//   collision aborts our runs), "events" (per agent, [[task id, timestep, "assigned" |
//   "finished"], ...]), "tasks" [[id, row, col], ...] by id.
// Letters: MAPF_T the Start-Kit's F forward, R clockwise, C counter-clockwise, W wait (T: a
// step the planner timed out, read as a wait). MAPF (PlanViz script/util.py
// state_transition_mapf): "R" col + 1 (east), "L" col - 1 (west), "U" row + 1 (rows grow
// downwards, so U moves DOWN the map as drawn), "D" row - 1, "W" wait.
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

// A LoRR map as the Start-Kit reads it (src/Grid.cpp): a MovingAI header ("type ...", "height H",
// "width W", "map") or a first line "rows,cols", then the rows; only '@' and 'T' are blocked,
// every other symbol is free (MovingAI's 'O' and 'W' included, unlike Grid::load). Throws
// LorrError naming the file and line for a malformed header or a row shorter than the width.
Grid load_lorr_map(const std::string& path);

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
  bool is_errand(int agent, Cell goal, Cell from) const override { return inner_.is_errand(agent, goal, from); }
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
// goal is assigned at t. A goal with id -1 (no task) is not reported; without ids, a goal equal
// to the cell it was drawn from is not. headings[i][t] (SimResult::headings) for a run in the
// rotation model, null for mapf.
nlohmann::json lorr_output(const Grid& grid, const std::vector<std::vector<Cell>>& paths,
                           const std::vector<std::vector<Cell>>& goals, int lookahead,
                           const std::vector<std::vector<long>>& task_ids = {},
                           const std::vector<std::vector<Heading>>* headings = nullptr);

// The executed paths of a LoRR output JSON, ours or the Start-Kit's (start + actualPaths
// replayed with the letters above; MAPF_T or MAPF), checked against the grid: a bad letter, a
// move off the map or into an obstacle is a LorrError naming `name`, the agent and the move.
// paths[i][t] as above; headings[i][t] too when asked (all east in MAPF).
std::vector<std::vector<Cell>> read_lorr_paths(const Grid& grid, const nlohmann::json& output, const std::string& name,
                                               std::vector<std::vector<Heading>>* headings = nullptr);

}  // namespace gdrhcr
