// See mapf_in_rotation.hpp (issue 23; LoRR Start-Kit v1.1.5's MAPF_T).
#include "gdrhcr/mapf_in_rotation.hpp"

#include <stdexcept>

namespace gdrhcr {

namespace {
// The first quarter turn from `heading` towards `target` (clockwise for a half turn).
Action turn_towards(Heading heading, Heading target) {
  return ((target - heading) & 3) == 3 ? Action::kCounterClockwise : Action::kClockwise;
}
}  // namespace

std::vector<Action> rotation_actions_for_step(const Grid& grid, const std::vector<Cell>& pos,
                                              const std::vector<Heading>& headings, const std::vector<Cell>& next) {
  const int n = static_cast<int>(pos.size());
  std::vector<Action> act(n, Action::kWait);
  std::vector<int> entering(grid.num_cells(), -1);  // the agent moving into a cell, if any
  std::vector<int> staying;
  for (int i = 0; i < n; ++i) {
    const Heading d = heading_of_move(grid, pos[i], next[i]);
    if (next[i] != pos[i] && d == kNoHeading)
      throw std::logic_error("rotation_actions_for_step: agent " + std::to_string(i) + " jumps from " +
                             grid.describe(pos[i]) + " to " + grid.describe(next[i]));
    if (d != kNoHeading && d == headings[i]) {
      act[i] = Action::kForward;
      entering[next[i]] = i;
    } else {
      if (d != kNoHeading) act[i] = turn_towards(headings[i], d);
      staying.push_back(i);
    }
  }
  while (!staying.empty()) {  // whoever moves into a staying agent's cell stays too
    const int i = staying.back();
    staying.pop_back();
    const int j = entering[pos[i]];
    if (j < 0 || act[j] != Action::kForward) continue;
    act[j] = Action::kWait;  // it faces its next cell already
    staying.push_back(j);
  }
  return act;
}

MapfInRotation::MapfInRotation(std::unique_ptr<Planner> inner, const Grid& grid, size_t dist_budget_bytes)
    : inner_(std::move(inner)), dist_(grid, ActionModel::kMapf, dist_budget_bytes) {}

StepReport MapfInRotation::plan_step(const WorldView& world, std::vector<Cell>& next) {
  if (!world.rotation() || !world.headings || !world.next_headings)
    throw std::invalid_argument("planner " + name() + " (mapf steps with turns and waits) plans in the rotation model only");
  const int n = world.num_agents();
  cells_.assign(n, kNoCell);
  WorldView view{world.grid, dist_, world.timestep, world.positions, world.goals, world.immovable, world.blocked};
  view.step_budget_s = world.step_budget_s;
  const StepReport report = inner_->plan_step(view, cells_);
  const std::vector<Action> act = rotation_actions_for_step(world.grid, world.positions, *world.headings, cells_);
  for (int i = 0; i < n; ++i) {
    const Pose p = apply_action(world.grid, world.pose(i), act[i]);
    next[i] = p.cell;
    (*world.next_headings)[i] = p.heading;
    forward_ += act[i] == Action::kForward;
    turns_ += act[i] == Action::kClockwise || act[i] == Action::kCounterClockwise;
    held_ += cells_[i] != world.positions[i] && act[i] != Action::kForward;
  }
  return report;
}

nlohmann::json MapfInRotation::stats() const {
  nlohmann::json j = inner_->stats();
  j["rotation_by"] = "mapf-wait";
  j["rotation_forward_moves"] = forward_;
  j["rotation_turns"] = turns_;
  j["rotation_held_moves"] = held_;
  return j;
}

TurnPlanning parse_turn_planning(const std::string& text) {
  if (text == "native") return TurnPlanning::kNative;
  if (text == "mapf-wait") return TurnPlanning::kMapfWait;
  throw std::invalid_argument("unknown turn planning '" + text + "' (expected native or mapf-wait)");
}

const char* turn_planning_name(TurnPlanning how) { return how == TurnPlanning::kNative ? "native" : "mapf-wait"; }

std::unique_ptr<Planner> make_planner_in(const PlannerParams& values, const Grid& grid, int num_agents, uint64_t seed,
                                         ActionModel model, TurnPlanning how) {
  if (model == ActionModel::kMapf || how == TurnPlanning::kNative)
    return make_planner(values, grid, num_agents, seed, model);
  return std::make_unique<MapfInRotation>(make_planner(values, grid, num_agents, seed, ActionModel::kMapf), grid);
}

}  // namespace gdrhcr
