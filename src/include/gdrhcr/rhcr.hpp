// RHCR: Rolling-Horizon Collision Resolution, with PBS over windowed SIPP and a PIBT fallback.
// Li, Tinka, Kiesel, Durham, Kumar, Koenig, "Lifelong Multi-Agent Path Finding in Large-Scale
// Warehouses", AAAI 2021; the baseline of GD-RHCR (DeWeese, Li, Qu), section "Simulations":
// PBS as the solver, PIBT as the fallback, alpha = 5, H = 20.
//
// Every alpha steps all agents are planned together with PBS (collision-free for H steps, each
// agent heading through its known goal sequence) and the plan is executed for alpha steps. A
// plan is dropped and PBS runs again at once when an agent is not where the plan says (a robot
// lagged). When PBS fails or hits its time limit or node budget, PIBT moves the agents until the
// next scheduled replan. RHCR has no soft constraints: every agent is in the one PBS call.
#pragma once

#include <vector>

#include "gdrhcr/pibt.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr {

struct RhcrConfig {
  int H = 20;              // planning window
  int alpha = 5;           // replanning period, 1 <= alpha <= H
  double timeout_s = 60;   // wall-clock limit of one PBS call
  long node_budget = 0;    // deterministic PBS node limit; 0 = none
};

class RhcrPlanner : public Planner {
 public:
  // In the rotation model PBS plans over (cell, heading) states (pbs.hpp, sipp.hpp), the plan
  // carries headings, and the fallback is PIBT in that model (pibt.hpp).
  RhcrPlanner(const Grid& grid, int num_agents, uint64_t seed, RhcrConfig config,
              ActionModel model = ActionModel::kMapf);
  std::string name() const override { return "rhcr"; }
  // StepReport{planned = true, plan_time_s = the PBS call's time} on steps where PBS ran.
  StepReport plan_step(const WorldView& world, std::vector<Cell>& next) override;
  nlohmann::json params() const override;
  nlohmann::json stats() const override;

  const RhcrConfig& config() const { return cfg_; }
  // Agent i's cells from the last planned step on; empty while PIBT moves the fleet.
  std::vector<Cell> planned_path(int agent) const override;

 private:
  bool on_plan(const WorldView& world) const;

  uint64_t seed_;
  RhcrConfig cfg_;
  ActionModel model_;
  PibtStep pibt_;
  std::vector<std::vector<Cell>> plan_;  // plan_[i][k]: agent i's cell k steps after plan_start_
  std::vector<std::vector<Heading>> plan_heads_;  // rotation: the headings of plan_
  int plan_start_ = 0;                   // timestep the plan (or the fallback period) started
  bool have_plan_ = false;               // else PIBT until plan_start_ + alpha
  bool started_ = false;
  int now_ = 0;  // the timestep of the last plan_step

  long solver_calls_ = 0, solver_failures_ = 0, timeouts_ = 0, fallback_steps_ = 0;
  long deviation_replans_ = 0, nodes_ = 0, sipp_calls_ = 0;
  double solver_time_sum_ = 0, solver_time_max_ = 0;
};

}  // namespace gdrhcr
