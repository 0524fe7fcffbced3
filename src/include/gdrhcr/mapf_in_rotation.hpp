// Our MAPF planners in the rotation action model by waiting for turns (issue 23; the model is the
// League of Robot Runners' MAPF_T, LoRR Start-Kit v1.1.5, see action_model.hpp). A planner built
// for the mapf model plans each step as it always does; the step is then executed as rotation
// actions, conservatively: an agent facing its next cell goes forward, one that does not turns
// towards it and stays, and whoever planned to move into the cell of an agent that stays, stays
// too (transitively), so the step stays free of vertex and edge conflicts. Planners replan from
// the positions they are given every step, so the lag costs no validity. The alternative to a
// planner's native rotation planning (gdrhcr_sim --turns mapf-wait), and what the LoRR adapter
// (lorr_adapter/) ran before the planners planned with turns.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr {

// A valid mapf step (pos -> next, as Planner::plan_step gives it) as rotation actions, as above.
// A half turn starts clockwise. Throws std::logic_error for a step that is not a wait or a move
// to a 4-neighbour.
std::vector<Action> rotation_actions_for_step(const Grid& grid, const std::vector<Cell>& pos,
                                              const std::vector<Heading>& headings, const std::vector<Cell>& next);

class MapfInRotation : public Planner {
 public:
  // `inner` was built for the mapf model on `grid`; it plans with its own mapf distance table.
  MapfInRotation(std::unique_ptr<Planner> inner, const Grid& grid, size_t dist_budget_bytes = DistTable::kDefaultBudgetBytes);
  std::string name() const override { return inner_->name(); }
  // `world` must be in the rotation model (check_action_model).
  StepReport plan_step(const WorldView& world, std::vector<Cell>& next) override;
  nlohmann::json params() const override { return inner_->params(); }
  // The inner planner's stats, plus "rotation_by" and the forward moves and turns executed and
  // the planned moves held back ("held_moves").
  nlohmann::json stats() const override;
  std::vector<PlannerGroup> groups() const override { return inner_->groups(); }
  std::vector<Cell> planned_path(int agent) const override { return inner_->planned_path(agent); }
  // The mapf distance rows the inner planner plans with.
  const DistTable& mapf_dist() const { return dist_; }

 private:
  std::unique_ptr<Planner> inner_;
  DistTable dist_;
  std::vector<Cell> cells_;
  long forward_ = 0, turns_ = 0, held_ = 0;
};

// How a planner moves in the rotation model: planning with headings itself (native), or its mapf
// steps executed with turns and waits (mapf-wait, MapfInRotation).
enum class TurnPlanning { kNative, kMapfWait };
// "native" or "mapf-wait"; throws std::invalid_argument naming a bad value and the choices.
TurnPlanning parse_turn_planning(const std::string& text);
const char* turn_planning_name(TurnPlanning how);
// LoRR runs (gdrhcr_sim --lorr-problem, the Start-Kit adapter) plan natively: the Start-Kit
// counts 2,755 errands of GD-RHCR that way on MR23-I-05 (400 agents, 1,000 steps, 100 ms per
// step) against 2,147 with mapf-wait (docs/results.md, "LoRR main round").
constexpr TurnPlanning kLorrTurnPlanning = TurnPlanning::kNative;

// The planner `values` names, built to move in `model`: in rotation natively (make_planner) or,
// with kMapfWait, its mapf self in MapfInRotation; in mapf `how` does not matter.
std::unique_ptr<Planner> make_planner_in(const PlannerParams& values, const Grid& grid, int num_agents, uint64_t seed,
                                         ActionModel model, TurnPlanning how);

}  // namespace gdrhcr
