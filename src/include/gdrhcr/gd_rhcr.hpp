// GD-RHCR: Group Decentralized Rolling-Horizon Collision Resolution.
// DeWeese, Li, Qu, "A Theoretical Framework for Parallel Lifelong MAPF Using Group
// Decentralized Planning" (Algorithm 1, section "Our Method").
//
// Every timestep: partition agents into groups (shortest-path distance <= V, transitively);
// a group whose agents all still follow one cached plan reuses it (lazy evaluation); otherwise
// it is replanned by the primary solver (PBS over SIPP, window H) with the other groups' plans
// from the end of the previous step as soft constraints of cost c_soft; groups of at least
// K_threshold agents, and groups whose primary solve fails or times out, are moved by the
// secondary solver (PIBT). Groups replanned in one step are solved concurrently on a oneTBB
// thread pool.
//
// Safety: for V >= 2 the paper's Dependence Time Lemma keeps groups planned apart from
// colliding in the next step. For any V, a final check runs on the assembled step; conflicting
// groups (and any group whose fixed move enters their cells) are re-moved together by PIBT,
// so an executed step is never in collision.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "gdrhcr/group_partition.hpp"
#include "gdrhcr/local_density.hpp"
#include "gdrhcr/local_guidance.hpp"
#include "gdrhcr/motion_forecast.hpp"
#include "gdrhcr/pibt.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/planner_params.hpp"
#include "gdrhcr/soft_constraint_table.hpp"
#include "gdrhcr/step_budget.hpp"
#include "gdrhcr/validator.hpp"

namespace gdrhcr {

struct GdRhcrConfig {
  int V = 2;                  // visibility: link agents at shortest-path distance <= V
  int H = 20;                 // planning window of the primary solver
  double c_soft = 1.0;        // cost of a conflict with another group's plan
  int k_threshold = 0;        // groups this large go to the secondary solver; 0 = the paper's
                              // default min(floor(0.1 k), 20), floored at 2 (see .cpp)
  double timeout_s = 60.0;    // wall-clock limit of one primary solve
  // Wall-clock budget of a whole step; 0 = none. Primary solves get its first 60% (groups not
  // solved by then are moved by the secondary solver, counted as budget_skips), guidance
  // searches stop at 85%.
  double step_budget_s = 0;
  long node_budget = 0;       // deterministic PBS node limit per solve; 0 = none
  int threads = 1;            // thread-pool size for groups replanned in one step
  std::string solver = "pbs";    // primary: pbs | pibt (the secondary solver is PIBT)
  // Groups in a crowded neighbourhood go to the secondary solver whatever their size: the
  // share of free cells holding an agent within `density_margin` cells of the group's bounding
  // box must be at most `max_density` for the primary solver (1 = no limit, as in the paper).
  double max_density = 1.0;
  int density_margin = 4;
  PibtOptions pibt;              // the secondary solver's PIBT techniques
  bool guidance = false;         // the secondary solver follows local guidance paths
  LocalGuidanceConfig lg;        // ... with these settings
  MotionForecastConfig forecast; // ... planned around its agents' motion forecast (steps >= 2)

};

// The configuration the parameter table's values give (the product default, the paper preset
// and every map-dependent rule live there: planner_params.cpp).
GdRhcrConfig gd_rhcr_config(const PlannerParams& values, uint64_t seed);

// Why a group was (re)planned this step, or not.
enum class GroupAction { Reused, Primary, ThresholdFallback, FailureFallback, Repair };
const char* to_string(GroupAction a);

struct GroupInfo {
  std::vector<int> agents;
  GroupAction action = GroupAction::Reused;
  double solve_time_s = 0;
};

class GdRhcrPlanner : public Planner {
 public:
  // In the rotation model (action_model.hpp) groups are formed with turns counted
  // (GroupPartition), the primary solver is PBS over SIPP on (cell, heading) states, plans carry
  // headings, and the secondary solver is PIBT in that model (pibt.hpp).
  GdRhcrPlanner(const Grid& grid, int num_agents, uint64_t seed, GdRhcrConfig config,
                ActionModel model = ActionModel::kMapf);
  ~GdRhcrPlanner() override;

  std::string name() const override { return "gd-rhcr"; }
  StepReport plan_step(const WorldView& world, std::vector<Cell>& next) override;
  nlohmann::json params() const override;
  nlohmann::json stats() const override;

  // The groups of the last step, with what each did (for rviz and diagnostics).
  const std::vector<GroupInfo>& last_groups() const { return last_groups_; }
  std::vector<PlannerGroup> groups() const override;
  // Agent i's planned cells from the current step on (its cached plan's remainder).
  std::vector<Cell> planned_path(int agent) const override;
  // The cell after `at` on the agent's guidance path (which holds the primary solver's plans too).
  Cell intended_next(int agent, Cell at) const override;
  int k_threshold() const { return k_threshold_; }

 private:
  struct Plan;
  struct Job;
  struct StepWork;
  // Algorithm 1, one step: partition into groups and pick each group's solver (reusing cached
  // plans lazily), solve the replanned groups in parallel, adopt their plans, move every agent,
  // then the final check with repair.
  void begin_step(const WorldView& world);
  void assign_groups(const WorldView& world, StepWork& work);
  void solve_groups(const WorldView& world, StepWork& work) const;
  void adopt_plans(const WorldView& world, StepWork& work);
  void move_agents(const WorldView& world, StepWork& work, std::vector<Cell>& next);
  void merge_and_repair(const WorldView& world, StepWork& work, std::vector<Cell>& next);
  void record_step(const StepWork& work);

  bool crowded(const WorldView& world, const std::vector<int>& group) const;
  bool needs_replan(const WorldView& world, const std::vector<int>& group) const;
  void index_agents(const WorldView& world);
  void collect_soft_constraints(const WorldView& world, const std::vector<int>& agents,
                                SoftConstraintTable& soft) const;
  std::vector<Cell> soft_path_of(const WorldView& world, int j) const;
  void solve_primary(const WorldView& world, Job& job) const;
  bool follows_guidance(const WorldView& world, int i, Cell to, Cell pref) const;
  void run_secondary(const WorldView& world, const std::vector<int>& agents,
                     const std::vector<Cell>& next, std::vector<Cell>& out);
  void keep_secondary_steps(const WorldView& world, const std::vector<int>& agents,
                            const std::vector<Cell>& next);
  void roll_forecast(const WorldView& world, const std::vector<int>& secondary,
                     const std::vector<uint8_t>& on_secondary, const std::vector<Cell>& next);
  bool repair_step(const WorldView& world, std::vector<Cell>& next, std::vector<uint8_t>& repaired);
  std::vector<int> repair_set(const WorldView& world, const std::vector<Cell>& next,
                              const std::vector<uint8_t>& repaired, int agent_a, int agent_b) const;

  const Grid& grid_;
  uint64_t seed_;
  GdRhcrConfig cfg_;
  ActionModel model_;
  int k_threshold_;
  GroupPartition partition_;
  PibtStep pibt_;
  std::unique_ptr<LocalGuidance> guidance_;  // paths of secondary agents and, as obstacles, plans
  std::unique_ptr<MotionForecast> forecast_;  // the secondary agents' motion, for the guidance
  StepValidator validator_;  // the final check, with its per-cell scratch kept across steps
  LocalDensity density_;
  StepBudget budget_;        // this step's
  static constexpr double kTailFade = 0.98;  // per step, of tail_s_
  double tail_s_ = 0;        // what steps with a hard limit did after PIBT's pushes, lately (record_step)
  std::vector<std::shared_ptr<const Plan>> plan_of_;  // lambda_i: the plan agent i follows
  std::vector<int> slot_of_;                          // agent i's row in that plan
  // Agents without a plan (the secondary solver's): their last step, from -> to, at step_at.
  std::vector<Cell> step_from_, step_to_;
  std::vector<int> step_at_;
  long next_plan_id_ = 1;
  int now_ = 0;  // the timestep of the last plan_step
  std::vector<GroupInfo> last_groups_;
  static constexpr int kBlock = 8;  // spatial index: agents per kBlock x kBlock cells
  std::vector<std::vector<int>> block_agents_;
  int blocks_w_ = 0;
  // This step's taken cells (immovable agents' and WorldView::blocked): blocked for every primary
  // solve, and the same per cell. Written before the parallel phase, read during it.
  std::vector<Cell> taken_cells_;
  std::vector<uint8_t> taken_at_;
  struct Arena;
  std::unique_ptr<Arena> arena_;

  // Statistics.
  long steps_ = 0, group_count_sum_ = 0, max_group_sum_ = 0, agents_sum_ = 0;
  long replanned_groups_ = 0, reused_groups_ = 0, primary_calls_ = 0;
  long density_fallbacks_ = 0, budget_skips_ = 0;
  long threshold_fallbacks_ = 0, failure_fallbacks_ = 0, timeouts_ = 0, repairs_ = 0;
  long pbs_nodes_ = 0, soft_conflicts_ = 0, solved_steps_ = 0;
  long guided_moves_ = 0, guidance_missed_ = 0;  // secondary moves with a guidance cell; not onto it
  double plan_time_sum_all_steps_ = 0, primary_time_sum_ = 0;
};

}  // namespace gdrhcr
