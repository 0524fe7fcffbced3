// The planner interface every lifelong solver implements (PIBT, RHCR, GD-RHCR), and the
// registry the command line and the ROS node use to build one by name from parameters.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/params.hpp"
#include "gdrhcr/planner_params.hpp"

namespace gdrhcr {

// What a planner sees at one timestep. goals[i][0] is agent i's current goal; goals[i][k] for
// k >= 1 are its next known goals (the lookahead; may be empty where tasks are not known yet).
struct WorldView {
  const Grid& grid;
  const DistTable& dist;
  int timestep;
  const std::vector<Cell>& positions;
  const std::vector<std::vector<Cell>>& goals;
  // Agents that cannot move (robots gone offline), per agent; null = none. Planners keep them
  // in place and plan around them; pair with a DistTable that blocks their cells, so distances
  // route around them too.
  const std::vector<uint8_t>* immovable = nullptr;
  // Free cells no agent may enter in this step and that may stay taken for a while, though no
  // agent stands on them (the cell a late robot is still leaving); null = none. Planners keep
  // agents out of them and plan around them; no agent's position is among them.
  const std::vector<Cell>* blocked = nullptr;
  // The action model in force (action_model.hpp). kMapf (the default): no headings, as before.
  // kRotation: headings[i] is agent i's heading now, and the planner writes agent i's heading at
  // timestep+1 into (*next_headings)[i] (sized to the fleet by the caller) beside next[i]; the
  // pair must be one action (F, R, C, W) from (positions[i], headings[i]). `dist` then holds
  // rotation rows (DistTable::action_model()).
  ActionModel action_model = ActionModel::kMapf;
  const std::vector<Heading>* headings = nullptr;
  std::vector<Heading>* next_headings = nullptr;
  // This step's wall-clock budget in seconds, from the call on (0 = the planner's own, if any):
  // a caller that spent part of its time already (the LoRR adapter's distance rows) hands on the
  // rest. Planners with a step budget (GD-RHCR) keep the smaller of the two.
  double step_budget_s = 0;
  // A hard limit on this step's time in seconds, from the call on (0 = none): where a budget is a
  // cap that must hold (the LoRR adapter's), PIBT stops planning agents at its share of it even in
  // a step that began past its budget, and the agents it has not reached step ahead or wait. The
  // budget above may be far smaller (it shrinks by what steps ran past it lately).
  double step_limit_s = 0;
  bool rotation() const { return action_model == ActionModel::kRotation; }
  Pose pose(int i) const { return {positions[i], headings ? (*headings)[i] : kEast}; }
  int num_agents() const { return static_cast<int>(positions.size()); }
  bool is_immovable(int i) const { return immovable && (*immovable)[i]; }
  // The cells nothing may enter in this step: the immovable agents' cells and the blocked cells;
  // and the same as a per-cell mask (empty when there are none).
  std::vector<Cell> taken_cells() const {
    std::vector<Cell> cells;
    for (int i = 0; immovable && i < num_agents(); ++i)
      if ((*immovable)[i]) cells.push_back(positions[i]);
    if (blocked) cells.insert(cells.end(), blocked->begin(), blocked->end());
    return cells;
  }
  std::vector<uint8_t> taken_cell_mask() const {
    std::vector<uint8_t> mask;
    if (!immovable && !(blocked && !blocked->empty())) return mask;
    mask.assign(grid.num_cells(), 0);
    for (Cell c : taken_cells()) mask[c] = 1;
    return mask;
  }
};

// A group of agents planned together in the last step, and the solver that moved it.
struct PlannerGroup {
  std::vector<int> agents;
  std::string solver;  // what moved it, e.g. GD-RHCR's "primary", "reused", "threshold_fallback"
};

struct StepReport {
  bool planned = false;     // a solver ran in this step (RHCR plans only every alpha steps)
  double plan_time_s = 0;   // the planner's plan-time metric for this step
};

class Planner {
 public:
  virtual ~Planner() = default;
  virtual std::string name() const = 0;
  // Fills next[i] with agent i's cell at timestep+1: a wait or a move to a 4-neighbour, with no
  // vertex or edge collision. Positions may differ from what the planner commanded before (a
  // robot may lag); planners must plan from the positions given. In the rotation model it also
  // fills (*world.next_headings)[i] (see WorldView); a planner built for the mapf model throws
  // std::invalid_argument when given a rotation world (check_action_model).
  virtual StepReport plan_step(const WorldView& world, std::vector<Cell>& next) = 0;
  // Every parameter in use, for the result record.
  virtual nlohmann::json params() const = 0;
  // Planner-specific counters for the result record (solver calls, fallbacks, groups, ...).
  virtual nlohmann::json stats() const { return nlohmann::json::object(); }
  // Introspection for visualisation (rviz markers, plots); call it between steps only.
  // The groups of the last step; empty for planners that do not group agents.
  virtual std::vector<PlannerGroup> groups() const { return {}; }
  // Agent i's planned cells from the current step on; empty when the planner keeps no plan.
  virtual std::vector<Cell> planned_path(int /*agent*/) const { return {}; }
  // After a step that took agent i to `at`: the cell the planner means it to enter at the step
  // after (planned_path one step further on), or kNoCell when it has none or `at` is off its path.
  // For executors that let a robot which lost time make an extra move; between steps only.
  virtual Cell intended_next(int agent, Cell at) const { return cell_after_step(planned_path(agent), at); }

 protected:
  // path[2] when path[1] is `at` and path[2] another cell (a path from the step just planned on),
  // else kNoCell.
  static Cell cell_after_step(const std::vector<Cell>& path, Cell at) {
    return path.size() >= 3 && path[1] == at && path[2] != at ? path[2] : kNoCell;
  }
};

// Planner names known to `make_planner`, in registration order.
std::vector<std::string> planner_names();
// Whether the named planner plans in the action model.
bool planner_supports(const std::string& name, ActionModel model);
// Throws std::invalid_argument naming `planner` when `world` is in another action model than the
// one the planner was built for.
void check_action_model(const std::string& planner, ActionModel built, const WorldView& world);
// Builds the planner with the values of the parameter table (PlannerParams::resolve), to plan in
// `model`. Throws ParamError naming the planner when it does not plan in that model.
std::unique_ptr<Planner> make_planner(const PlannerParams& values, const Grid& grid, int num_agents,
                                      uint64_t seed, ActionModel model = ActionModel::kMapf);
// Resolves `params` (e.g. --H 20 from the command line or a ROS parameter) against the planner's
// table and builds it. Throws ParamError naming an unknown planner, an unknown parameter or a
// bad value.
std::unique_ptr<Planner> make_planner(const std::string& name, Params& params, const Grid& grid,
                                      int num_agents, uint64_t seed, ActionModel model = ActionModel::kMapf);

}  // namespace gdrhcr
