#include "gdrhcr/gd_rhcr.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <limits>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <tbb/task_arena.h>

#include "gdrhcr/pbs.hpp"
#include "gdrhcr/validator.hpp"
#include "tsan_annotations.hpp"

namespace gdrhcr {

using Clock = std::chrono::steady_clock;

const char* to_string(GroupAction a) {
  switch (a) {
    case GroupAction::Reused: return "reused";
    case GroupAction::Primary: return "primary";
    case GroupAction::ThresholdFallback: return "threshold_fallback";
    case GroupAction::FailureFallback: return "failure_fallback";
    case GroupAction::Repair: return "repair";
  }
  return "?";
}

// One solve's output, shared by every agent that follows it (the paper's lambda_i).
// paths[slot][k] is the agent's cell at timestep start_time + k; steps k -> k+1 for
// k < valid_steps are collision-free among the plan's agents.
struct GdRhcrPlanner::Plan {
  long id = 0;
  int start_time = 0;
  int valid_steps = 0;
  std::vector<std::vector<Cell>> paths;
  std::vector<std::vector<Heading>> headings;  // rotation: headings[slot][k], as paths
  std::vector<std::vector<Cell>> goals;  // the goal sequence each agent was planned with
  std::vector<uint8_t> held;             // per agent: immovable when planned (its path just stays)
};

// A group replanned by the primary solver this step.
struct GdRhcrPlanner::Job {
  size_t group_index = 0;
  const std::vector<int>* agents = nullptr;
  PbsResult result;
  bool budget_skipped = false;  // not started: the step budget was used up
};

// What one step decided for its groups.
struct GdRhcrPlanner::StepWork {
  std::vector<Job> jobs;                 // groups the primary solver replans
  std::vector<size_t> secondary_groups;  // groups the secondary solver moves
  std::vector<int> secondary;            // their agents, and the agents the final check re-moved
  std::vector<uint8_t> on_secondary;     // per agent
  double max_solve_time = 0;             // the step's plan-time metric
};

struct GdRhcrPlanner::Arena {
  explicit Arena(int threads) : arena(threads) {}
  tbb::task_arena arena;
};

namespace {
// The smallest box (x0, y0, x1, y1) holding the agents' cells.
std::array<int, 4> bounding_box(const Grid& grid, const WorldView& world, const std::vector<int>& agents) {
  int x0 = grid.width(), x1 = -1, y0 = grid.height(), y1 = -1;
  for (int i : agents) {
    x0 = std::min(x0, grid.x_of(world.positions[i]));
    x1 = std::max(x1, grid.x_of(world.positions[i]));
    y0 = std::min(y0, grid.y_of(world.positions[i]));
    y1 = std::max(y1, grid.y_of(world.positions[i]));
  }
  return {x0, y0, x1, y1};
}

// One soft-constraint table per thread, reused: clearing it costs what was added, not the map's size.
SoftConstraintTable& thread_soft_table(const Grid& grid) {
  thread_local std::unique_ptr<SoftConstraintTable> table;
  thread_local const Grid* table_grid = nullptr;
  thread_local int table_cells = 0;
  if (!table || table_grid != &grid || table_cells != grid.num_cells()) {
    table = std::make_unique<SoftConstraintTable>(grid);
    table_grid = &grid;
    table_cells = grid.num_cells();
  }
  table->clear();
  return *table;
}
}  // namespace

GdRhcrPlanner::GdRhcrPlanner(const Grid& grid, int num_agents, uint64_t seed, GdRhcrConfig config,
                             ActionModel model)
    : grid_(grid),
      seed_(seed),
      cfg_(std::move(config)),
      model_(model),
      // The paper's K_threshold = min(floor(0.1 k), 20), floored at 2 (planner_params.cpp's rule).
      k_threshold_(cfg_.k_threshold > 0 ? cfg_.k_threshold : std::max(2, std::min(num_agents / 10, 20))),
      partition_(grid),
      pibt_(grid, num_agents, seed, cfg_.pibt),
      guidance_(cfg_.guidance ? std::make_unique<LocalGuidance>(grid, num_agents, cfg_.lg) : nullptr),
      forecast_(cfg_.guidance && cfg_.forecast.steps >= 2
                    ? std::make_unique<MotionForecast>(grid, num_agents, cfg_.forecast, cfg_.lg)
                    : nullptr),
      validator_(grid, model),
      density_(grid),
      plan_of_(num_agents),
      slot_of_(num_agents, 0),
      step_from_(num_agents, kNoCell),
      step_to_(num_agents, kNoCell),
      step_at_(num_agents, -1),
      arena_(std::make_unique<Arena>(std::max(1, cfg_.threads))) {
  if (cfg_.V < 0) throw ParamError("gd-rhcr: V must be >= 0, got " + std::to_string(cfg_.V));
  if (cfg_.H < 1) throw ParamError("gd-rhcr: H must be >= 1, got " + std::to_string(cfg_.H));
  if (!(cfg_.c_soft >= 0)) throw ParamError("gd-rhcr: c_soft must be >= 0");
  if (cfg_.threads < 1) throw ParamError("gd-rhcr: threads must be >= 1");
  if (!(cfg_.timeout_s > 0)) throw ParamError("gd-rhcr: timeout must be > 0");
  if (!(cfg_.step_budget_s >= 0)) throw ParamError("gd-rhcr: step budget must be >= 0 seconds");
  if (cfg_.node_budget < 0) throw ParamError("gd-rhcr: node budget must be >= 0");
  if (cfg_.solver != "pbs" && cfg_.solver != "pibt")
    throw ParamError("gd-rhcr: solver must be pbs or pibt, got '" + cfg_.solver + "'");
}

GdRhcrPlanner::~GdRhcrPlanner() = default;

// Algorithm 1, one timestep.
StepReport GdRhcrPlanner::plan_step(const WorldView& world, std::vector<Cell>& next) {
  check_action_model(name(), model_, world);
  StepWork work;
  begin_step(world);
  assign_groups(world, work);        // groups, and which solver moves each (lines 3-10, 19)
  solve_groups(world, work);         // the replanned groups, in parallel (lines 11-12)
  adopt_plans(world, work);          // lambda_i <- P; failed solves to the secondary solver (13-16)
  move_agents(world, work, next);    // advance along lambda_i; the secondary solver moves the rest
  merge_and_repair(world, work, next);
  record_step(work);
  return {!work.jobs.empty() || !work.secondary.empty(), work.max_solve_time};
}

// Line 3: the groups (connected components at distance <= V), and what every solve of this step
// reads: the density around groups, agents by map block, the step budget, the taken cells.
void GdRhcrPlanner::begin_step(const WorldView& world) {
  now_ = world.timestep;
  double budget_s = cfg_.step_budget_s;
  if (world.step_budget_s > 0) budget_s = budget_s > 0 ? std::min(budget_s, world.step_budget_s) : world.step_budget_s;
  // A hard limit stops PIBT's pushes early by what the last steps did after them.
  const double limit_s = world.step_limit_s > 0 ? std::max(1e-6, world.step_limit_s - tail_s_) : 0;
  budget_ = StepBudget(StepBudget::Clock::now(), budget_s, limit_s);
  if (world.rotation()) partition_.compute(world.positions, *world.headings, cfg_.V);
  else partition_.compute(world.positions, cfg_.V);
  if (cfg_.max_density < 1.0) density_.count(world.positions);
  index_agents(world);
  taken_cells_ = world.taken_cells();
  taken_at_ = world.taken_cell_mask();
}

// The product's density rule: a group in a crowded neighbourhood goes to the secondary solver.
bool GdRhcrPlanner::crowded(const WorldView& world, const std::vector<int>& group) const {
  return cfg_.max_density < 1.0 &&
         density_.around(bounding_box(grid_, world, group), cfg_.density_margin) > cfg_.max_density;
}

// Each group goes to the secondary solver (K_threshold, or crowded), the primary solver (its
// cached plan does not hold: the lazy test), or reuses its plan.
void GdRhcrPlanner::assign_groups(const WorldView& world, StepWork& work) {
  const auto& groups = partition_.groups();
  last_groups_.assign(groups.size(), GroupInfo{});
  for (size_t g = 0; g < groups.size(); ++g) {
    last_groups_[g].agents = groups[g];
    const bool crowd = crowded(world, groups[g]);
    if (crowd) ++density_fallbacks_;
    if (static_cast<int>(groups[g].size()) >= k_threshold_ || cfg_.solver == "pibt" || crowd) {
      last_groups_[g].action = GroupAction::ThresholdFallback;
      work.secondary_groups.push_back(g);
    } else if (needs_replan(world, groups[g])) {
      last_groups_[g].action = GroupAction::Primary;
      Job job;
      job.group_index = g;
      job.agents = &groups[g];
      work.jobs.push_back(std::move(job));
    } else {
      last_groups_[g].action = GroupAction::Reused;
    }
  }
}

// The primary solves, in parallel, larger groups first so the slowest solve starts early. Each
// reads only the plans as they stood before this step.
void GdRhcrPlanner::solve_groups(const WorldView& world, StepWork& work) const {
  auto& jobs = work.jobs;
  std::vector<size_t> order(jobs.size());
  for (size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return jobs[a].agents->size() > jobs[b].agents->size(); });
  GDRHCR_TSAN_RELEASE(&jobs);
  arena_->arena.execute([&] {
    tbb::parallel_for(tbb::blocked_range<size_t>(0, order.size(), 1),
                      [&](const tbb::blocked_range<size_t>& r) {
                        GDRHCR_TSAN_ACQUIRE(&jobs);
                        for (size_t k = r.begin(); k != r.end(); ++k) solve_primary(world, jobs[order[k]]);
                        GDRHCR_TSAN_RELEASE(&jobs);
                      },
                      // One group per task: solves differ wildly in cost, so no chunking (and
                      // no auto_partitioner, whose benign steal flag ThreadSanitizer reports).
                      tbb::simple_partitioner());
  });
  GDRHCR_TSAN_ACQUIRE(&jobs);
}

// Solved plans become the groups' lambda_i (and obstacles for the guidance searches); failed
// solves go to the secondary solver.
void GdRhcrPlanner::adopt_plans(const WorldView& world, StepWork& work) {
  for (Job& job : work.jobs) {
    ++primary_calls_;
    pbs_nodes_ += job.result.nodes;
    primary_time_sum_ += job.result.time_s;
    work.max_solve_time = std::max(work.max_solve_time, job.result.time_s);
    last_groups_[job.group_index].solve_time_s = job.result.time_s;
    if (job.result.timed_out) ++timeouts_;
    if (job.budget_skipped) ++budget_skips_;
    if (!job.result.success) {
      ++failure_fallbacks_;
      last_groups_[job.group_index].action = GroupAction::FailureFallback;
      work.secondary_groups.push_back(job.group_index);
      continue;
    }
    soft_conflicts_ += job.result.soft_conflicts;
    auto plan = std::make_shared<Plan>();
    plan->id = next_plan_id_++;
    plan->start_time = world.timestep;
    plan->valid_steps = cfg_.H;
    plan->paths = std::move(job.result.paths);
    plan->headings = std::move(job.result.headings);
    for (size_t s = 0; s < job.agents->size(); ++s) {
      const int i = (*job.agents)[s];
      plan->goals.push_back(world.goals[i]);
      plan->held.push_back(world.is_immovable(i));
      plan_of_[i] = plan;
      slot_of_[i] = static_cast<int>(s);
      if (guidance_) guidance_->set_path(i, world.timestep, plan->paths[s]);
    }
  }
}

// Line 22: every agent on a (new or cached) multi-step plan takes its next planned cell; one
// secondary-solver call moves the agents of every group sent there.
void GdRhcrPlanner::move_agents(const WorldView& world, StepWork& work, std::vector<Cell>& next) {
  const int n = world.num_agents(), t = world.timestep;
  std::fill(next.begin(), next.end(), kNoCell);
  work.on_secondary.assign(n, 0);
  for (size_t g : work.secondary_groups)
    for (int i : partition_.groups()[g]) work.on_secondary[i] = 1, work.secondary.push_back(i);
  for (int i = 0; i < n; ++i) {
    if (work.on_secondary[i]) continue;
    const auto& path = plan_of_[i]->paths[slot_of_[i]];
    const int k = std::min<int>(t - plan_of_[i]->start_time + 1, path.size() - 1);
    next[i] = path[k];
    if (world.rotation()) (*world.next_headings)[i] = plan_of_[i]->headings[slot_of_[i]][k];
  }
  if (!work.secondary.empty()) {
    const auto t0 = Clock::now();
    if (forecast_) forecast_->seed(world, work.secondary, *guidance_);
    run_secondary(world, work.secondary, next, next);
    const double dt = std::chrono::duration<double>(Clock::now() - t0).count();
    work.max_solve_time = std::max(work.max_solve_time, dt);
    for (size_t g : work.secondary_groups) last_groups_[g].solve_time_s += dt;
  }
  for (auto& info : last_groups_) threshold_fallbacks_ += info.action == GroupAction::ThresholdFallback;
}

// The final check; agents it re-moved and the secondary solver's agents are left without a plan, so
// they are reconsidered (and maybe handed back to the primary solver) at the next step; then the
// secondary agents' motion forecast for the next step's guidance.
void GdRhcrPlanner::merge_and_repair(const WorldView& world, StepWork& work, std::vector<Cell>& next) {
  std::vector<uint8_t> repaired(world.num_agents(), 0);
  if (repair_step(world, next, repaired)) {
    for (int i = 0; i < world.num_agents(); ++i)
      if (repaired[i] && !work.on_secondary[i]) work.on_secondary[i] = 1, work.secondary.push_back(i);
    for (auto& info : last_groups_)
      if (repaired[info.agents[0]]) info.action = GroupAction::Repair;
  }
  keep_secondary_steps(world, work.secondary, next);
  if (forecast_ && !work.secondary.empty()) roll_forecast(world, work.secondary, work.on_secondary, next);
}

void GdRhcrPlanner::record_step(const StepWork& work) {
  // How long the step went on after PIBT's pushes (turns, the final check, the forecast): with a
  // hard limit the next step's pushes stop that much earlier. A slowly fading maximum.
  if (budget_.limit != StepBudget::Clock::time_point::max() && pibt_.pushed_at() >= budget_.start) {
    const double tail = std::chrono::duration<double>(StepBudget::Clock::now() - pibt_.pushed_at()).count();
    tail_s_ = std::max(tail, kTailFade * tail_s_);
  }
  const auto& groups = partition_.groups();
  ++steps_;
  group_count_sum_ += static_cast<long>(groups.size());
  size_t max_size = 0, agents = 0;
  for (auto& g : groups) max_size = std::max(max_size, g.size()), agents += g.size();
  agents_sum_ += static_cast<long>(agents);
  max_group_sum_ += static_cast<long>(max_size);
  replanned_groups_ += static_cast<long>(work.jobs.size());
  for (auto& info : last_groups_) reused_groups_ += info.action == GroupAction::Reused;
  plan_time_sum_all_steps_ += work.max_solve_time;
  if (!work.jobs.empty() || !work.secondary.empty()) ++solved_steps_;
}

std::vector<PlannerGroup> GdRhcrPlanner::groups() const {
  std::vector<PlannerGroup> out;
  out.reserve(last_groups_.size());
  for (auto& g : last_groups_) out.push_back({g.agents, to_string(g.action)});
  return out;
}

std::vector<Cell> GdRhcrPlanner::planned_path(int agent) const {
  if (agent < 0 || agent >= static_cast<int>(plan_of_.size())) return {};
  const auto& plan = plan_of_[agent];
  if (!plan) return step_at_[agent] == now_ ? std::vector<Cell>{step_from_[agent], step_to_[agent]} : std::vector<Cell>{};
  const auto& path = plan->paths[slot_of_[agent]];
  const int from = std::clamp(now_ - plan->start_time, 0, static_cast<int>(path.size()) - 1);
  return std::vector<Cell>(path.begin() + from, path.end());
}

Cell GdRhcrPlanner::intended_next(int agent, Cell at) const {
  if (!guidance_) return Planner::intended_next(agent, at);
  return cell_after_step(guidance_->path_from(agent, now_), at);
}

// Algorithm 1's lazy test: replan when the agents' plans come from different solves (someone
// joined), when the plan is exhausted, and also, beyond the paper, when an agent is not where
// its plan says (a lagging robot) or its current goal was not among the goals the plan was made
// for (a task that arrived after the plan, as in the ROS node where future tasks are unknown).
bool GdRhcrPlanner::needs_replan(const WorldView& world, const std::vector<int>& group) const {
  const int t = world.timestep;
  const Plan* first = plan_of_[group[0]].get();
  if (!first) return true;
  for (int i : group) {
    const Plan* p = plan_of_[i].get();
    if (p != first) return true;
    const int k = t - p->start_time;
    if (k < 0 || k >= p->valid_steps) return true;
    const auto& path = p->paths[slot_of_[i]];
    if (k + 1 >= static_cast<int>(path.size()) || path[k] != world.positions[i]) return true;
    if (world.rotation() && p->headings[slot_of_[i]][k] != (*world.headings)[i]) return true;
    if (world.is_immovable(i) && path[k + 1] != path[k]) return true;  // went offline since
    // Free again (a late robot arrived, an offline one came back): its plan only kept it in place.
    if (!p->held.empty() && p->held[slot_of_[i]] && !world.is_immovable(i)) return true;
    if (!taken_at_.empty())  // the plan runs into a robot that went offline or a cell blocked since
      for (size_t s = k + 1; s < path.size(); ++s)
        if (taken_at_[path[s]] && path[s] != world.positions[i]) return true;
    const Cell goal = world.goals[i].empty() ? kNoCell : world.goals[i][0];
    const auto& planned_goals = p->goals[slot_of_[i]];
    if (goal != kNoCell && std::find(planned_goals.begin(), planned_goals.end(), goal) == planned_goals.end())
      return true;
  }
  return false;
}

// Agents by blocks of kBlock x kBlock cells, so each group's soft constraints visit only the
// agents near it instead of every agent.
void GdRhcrPlanner::index_agents(const WorldView& world) {
  blocks_w_ = (grid_.width() + kBlock - 1) / kBlock;
  const int blocks_h = (grid_.height() + kBlock - 1) / kBlock;
  block_agents_.resize(static_cast<size_t>(blocks_w_) * blocks_h);
  for (auto& b : block_agents_) b.clear();
  for (int j = 0; j < world.num_agents(); ++j) {
    const Cell c = world.positions[j];
    block_agents_[static_cast<size_t>(grid_.y_of(c) / kBlock) * blocks_w_ + grid_.x_of(c) / kBlock].push_back(j);
  }
}

// What agent j (outside the group being solved) is expected to do, as a soft constraint: its
// plan from the end of the previous step, up to H steps; for an agent the secondary solver moves,
// its guidance path; else staying where it is.
std::vector<Cell> GdRhcrPlanner::soft_path_of(const WorldView& world, int j) const {
  const int t = world.timestep;
  std::vector<Cell> rest;
  const Plan* p = plan_of_[j].get();
  const int k = p ? t - p->start_time : -1;
  if (p && k >= 0 && k < static_cast<int>(p->paths[slot_of_[j]].size()) &&
      p->paths[slot_of_[j]][k] == world.positions[j]) {
    const auto& path = p->paths[slot_of_[j]];
    const int end = std::min<int>(path.size(), k + cfg_.H + 1);
    rest.assign(path.begin() + k, path.begin() + end);
  }
  if (rest.size() <= 1 && guidance_ && guidance_->next_cell(j, t, world.positions[j]) != kNoCell) {
    rest = guidance_->path_from(j, t);
    if (static_cast<int>(rest.size()) > cfg_.H + 1) rest.resize(cfg_.H + 1);
  }
  if (rest.empty()) rest.push_back(world.positions[j]);
  return rest;
}

// Line 11: the soft constraints of the agents outside the group that could meet it within H
// steps: Manhattan distance (a lower bound on the path distance) at most 2H from the group's
// bounding box, found through the blocks of the spatial index that overlap that box.
void GdRhcrPlanner::collect_soft_constraints(const WorldView& world, const std::vector<int>& agents,
                                             SoftConstraintTable& soft) const {
  const auto [x0, y0, x1, y1] = bounding_box(grid_, world, agents);
  const int margin = 2 * cfg_.H;
  const int my_group = partition_.group_of(agents[0]);
  const int bx0 = std::max(0, x0 - margin) / kBlock, bx1 = std::min(grid_.width() - 1, x1 + margin) / kBlock;
  const int by0 = std::max(0, y0 - margin) / kBlock, by1 = std::min(grid_.height() - 1, y1 + margin) / kBlock;
  for (int by = by0; by <= by1; ++by)
    for (int bx = bx0; bx <= bx1; ++bx)
      for (int j : block_agents_[static_cast<size_t>(by) * blocks_w_ + bx]) {
        if (partition_.group_of(j) == my_group) continue;
        const int x = grid_.x_of(world.positions[j]), y = grid_.y_of(world.positions[j]);
        if (x < x0 - margin || x > x1 + margin || y < y0 - margin || y > y1 + margin) continue;
        soft.add_path(soft_path_of(world, j));
      }
}

// Line 12: PBS over SIPP for one group, window H, against the soft constraints. Immovable agents
// (offline robots) are not planned: every path avoids their cells (hard: they will not move).
void GdRhcrPlanner::solve_primary(const WorldView& world, Job& job) const {
  const std::vector<int>& agents = *job.agents;
  const auto t_start = Clock::now();
  SoftConstraintTable& soft = thread_soft_table(grid_);
  if (cfg_.c_soft > 0) collect_soft_constraints(world, agents, soft);
  std::vector<Cell> starts;
  std::vector<std::vector<Cell>> goals;
  std::vector<Heading> headings;
  for (int i : agents)
    if (!world.is_immovable(i))
      starts.push_back(world.positions[i]), goals.push_back(world.goals[i]), headings.push_back(world.pose(i).heading);
  PbsConfig pc;
  pc.horizon = cfg_.H;
  pc.c_soft = cfg_.c_soft;
  pc.time_limit_s = cfg_.timeout_s;
  pc.node_budget = cfg_.node_budget;
  pc.blocked_cells = taken_cells_.empty() ? nullptr : &taken_cells_;
  pc.start_headings = world.rotation() ? &headings : nullptr;
  if (budget_.solves != Clock::time_point::max()) {  // the step budget: give up if nothing is left
    const double left = std::chrono::duration<double>(budget_.solves - Clock::now()).count();
    if (left <= 0) {
      job.result = PbsResult{};
      job.result.timed_out = true;
      job.budget_skipped = true;
      job.result.time_s = std::chrono::duration<double>(Clock::now() - t_start).count();
      return;
    }
    pc.time_limit_s = std::min(pc.time_limit_s, left);
  }
  job.result = solve_pbs(grid_, world.dist, starts, goals, soft.empty() ? nullptr : &soft, pc);
  job.result.time_s = std::chrono::duration<double>(Clock::now() - t_start).count();  // soft constraints included
  if (job.result.success && starts.size() != agents.size()) {  // back in group order
    std::vector<std::vector<Cell>> paths(agents.size());
    std::vector<std::vector<Heading>> heads(world.rotation() ? agents.size() : 0);
    for (size_t a = 0, k = 0; a < agents.size(); ++a) {
      const bool held = world.is_immovable(agents[a]);
      if (world.rotation())
        heads[a] = held ? std::vector<Heading>(cfg_.H + 1, world.pose(agents[a]).heading) : std::move(job.result.headings[k]);
      paths[a] = held ? std::vector<Cell>(cfg_.H + 1, world.positions[agents[a]]) : std::move(job.result.paths[k++]);
    }
    job.result.paths = std::move(paths);
    job.result.headings = std::move(heads);
  }
}

// The secondary solver's agents (and those the final check re-moved) follow no plan: their
// groups are replanned at the next step (Algorithm 1's lazy test fails on a missing plan, as it
// would on an exhausted one-step plan), so only the step itself is kept, for planned_path. No
// plan object per group: with 10,000 agents they cost a third of the step.
void GdRhcrPlanner::keep_secondary_steps(const WorldView& world, const std::vector<int>& agents,
                                         const std::vector<Cell>& next) {
  for (int i : agents) {
    plan_of_[i].reset();
    step_from_[i] = world.positions[i], step_to_[i] = next[i], step_at_[i] = world.timestep;
  }
}

// Whether agent i's move to `to` is the one its guidance path makes now: into the path's next
// cell, or staying where the path stays. In the rotation model a path keeps its cell while it
// turns, so staying and turning towards the next cell the path goes to (`pref`) follows it too.
bool GdRhcrPlanner::follows_guidance(const WorldView& world, int i, Cell to, Cell pref) const {
  const Cell at = world.positions[i];
  if (to == guidance_->next_cell(i, world.timestep, at)) return true;
  if (!world.rotation() || to != at || pref == at) return false;
  const Heading want = heading_of_move(grid_, at, pref);
  return want != kNoHeading &&
         turn_steps((*world.next_headings)[i], want) < turn_steps(world.pose(i).heading, want);
}

// Moves `agents` with PIBT while every other agent keeps the move in `out`.
void GdRhcrPlanner::run_secondary(const WorldView& world, const std::vector<int>& agents,
                                  const std::vector<Cell>& fixed_next, std::vector<Cell>& out) {
  std::vector<uint8_t> in_set(world.num_agents(), 0);
  for (int i : agents) in_set[i] = 1;
  std::vector<std::pair<Cell, Cell>> fixed;
  for (int j = 0; j < world.num_agents(); ++j)
    if (!in_set[j] && fixed_next[j] != kNoCell) fixed.emplace_back(world.positions[j], fixed_next[j]);
  std::vector<Cell> moves(world.num_agents(), kNoCell);
  if (guidance_) {
    // Guidance first, the highest priorities first; PIBT then tries each agent's next cell.
    std::vector<int> order(agents);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return pibt_.priority(a) > pibt_.priority(b); });
    arena_->arena.execute([&] { guidance_->update(world, order, budget_.guidance, budget_.refine); });  // banded: threads
    std::vector<Cell> preferred(world.num_agents(), kNoCell);
    for (int i : agents)
      preferred[i] = world.rotation() ? guidance_->next_move(i, world.timestep, world.positions[i])
                                      : guidance_->next_cell(i, world.timestep, world.positions[i]);
    pibt_.set_deadline(budget_.secondary, budget_.start, budget_.limit);
    pibt_.step(world, moves, agents, fixed, &preferred);
    for (int i : agents) {  // how often the guidance foretold the move (it had a cell for it)
      if (preferred[i] == kNoCell) continue;
      ++guided_moves_;
      if (!follows_guidance(world, i, moves[i], preferred[i])) ++guidance_missed_;
    }
  } else {
    pibt_.set_deadline(budget_.secondary, budget_.start, budget_.limit);
    pibt_.step(world, moves, agents, fixed);
  }
  for (int i : agents) out[i] = moves[i];
}

// The secondary agents' motion forecast for the next step's guidance; agents on multi-step
// plans follow them in the rollout.
void GdRhcrPlanner::roll_forecast(const WorldView& world, const std::vector<int>& secondary,
                                  const std::vector<uint8_t>& on_secondary, const std::vector<Cell>& next) {
  const int t = world.timestep;
  std::vector<std::vector<Cell>> fixed(world.num_agents());
  for (int i = 0; i < world.num_agents(); ++i) {
    if (on_secondary[i] || !plan_of_[i]) continue;
    const auto& path = plan_of_[i]->paths[slot_of_[i]];
    const int k = t + 1 - plan_of_[i]->start_time;
    if (k >= 0 && k < static_cast<int>(path.size()) && path[k] == next[i]) fixed[i].assign(path.begin() + k, path.end());
  }
  forecast_->roll(world, next, secondary, pibt_, *guidance_, &fixed, budget_.guidance);
}

// The agents the final check re-moves together: the groups of the colliding pair and of every
// agent repaired before, closed under "a fixed agent moving into the cell of a re-moved agent
// joins them" (PIBT must be free to keep an agent in place).
std::vector<int> GdRhcrPlanner::repair_set(const WorldView& world, const std::vector<Cell>& next,
                                           const std::vector<uint8_t>& repaired, int agent_a, int agent_b) const {
  std::vector<uint8_t> in_set(world.num_agents(), 0);
  std::vector<int> agents;
  auto add_group = [&](int a) {
    if (a < 0 || in_set[a]) return;
    for (int m : partition_.groups()[partition_.group_of(a)])
      if (!in_set[m]) in_set[m] = 1, agents.push_back(m);
  };
  for (int i = 0; i < world.num_agents(); ++i)
    if (repaired[i]) add_group(i);
  add_group(agent_a);
  add_group(agent_b);
  std::vector<int> agent_at(grid_.num_cells(), -1);
  for (int i = 0; i < world.num_agents(); ++i) agent_at[world.positions[i]] = i;
  for (bool grew = true; grew;) {
    grew = false;
    for (int j = 0; j < world.num_agents(); ++j) {
      if (in_set[j]) continue;
      const int k = agent_at[next[j]];
      if (k >= 0 && k != j && in_set[k]) add_group(j), grew = true;
    }
  }
  return agents;
}

// The final check: if the assembled step has a collision (possible only for V < 2 or with
// stale plans), the agents of repair_set are re-moved together by PIBT with every other move
// fixed. Returns true when anything was repaired. Every round re-moves more agents than the
// last; a collision that stays with no new agent to re-move cannot be repaired (the input is
// impossible, e.g. two agents in one cell) and throws instead of looping for ever.
bool GdRhcrPlanner::repair_step(const WorldView& world, std::vector<Cell>& next,
                                std::vector<uint8_t>& repaired) {
  bool any = false;
  size_t last_round = 0;
  for (;;) {
    auto v = validator_.check(world.positions, next, world.headings, world.next_headings);
    if (!v) return any;
    any = true;
    const std::vector<int> agents = repair_set(world, next, repaired, v->agent_a, v->agent_b);
    if (last_round > 0 && agents.size() <= last_round)
      throw std::runtime_error("gd-rhcr: no collision-free step: " + v->describe(grid_, world.timestep) +
                               " persists with every agent involved re-moved (do two agents start in one cell?)");
    last_round = agents.size();
    std::vector<Cell> fixed_next(next);
    for (int i : agents) fixed_next[i] = kNoCell;
    run_secondary(world, agents, fixed_next, next);
    for (int i : agents) repaired[i] = 1;
    ++repairs_;
  }
}

nlohmann::json GdRhcrPlanner::params() const {
  return {{"action_model", action_model_name(model_)},
          {"V", cfg_.V},
          {"H", cfg_.H},
          {"c_soft", cfg_.c_soft},
          {"k_threshold", k_threshold_},
          {"timeout", cfg_.timeout_s},
          {"step_budget", cfg_.step_budget_s},
          {"node_budget", cfg_.node_budget},
          {"threads", cfg_.threads},
          {"solver", cfg_.solver},
          {"max_density", cfg_.max_density},
          {"density_margin", cfg_.density_margin},
          {"swap", cfg_.pibt.swap},
          {"priority_reset", cfg_.pibt.priority_reset},
          {"tie_break", cfg_.pibt.tie_break == PibtOptions::TieBreak::kRandom ? "random" : "free-first"},
          {"rotation_pibt", PibtOptions::name(cfg_.pibt.rotation)},
          {"guidance", cfg_.guidance ? "local" : "none"},
          {"lg_window", cfg_.lg.window},
          {"lg_cost", cfg_.lg.collision_cost},
          {"lg_cost_per_kind", cfg_.lg.cost_per_kind},
          {"lg_far_cost", cfg_.lg.far_collision_cost},
          {"lg_near_steps", cfg_.lg.near_steps},
          {"lg_contraflow", cfg_.lg.contraflow_cost},
          {"lg_lazy", cfg_.lg.lazy},
          {"lg_straight", cfg_.lg.straight},
          {"lg_recheck", cfg_.lg.recheck},
          {"lg_keep", cfg_.lg.keep},
          {"lg_expansions", cfg_.lg.max_expansions},
          {"lg_blocked_steps", cfg_.lg.blocked_steps},
          {"lg_phases", cfg_.lg.phases},
          {"lg_forecast", forecast_ ? cfg_.forecast.steps : 0},
          {"lg_forecast_window", cfg_.forecast.window},
          {"seed", seed_}};
}

nlohmann::json GdRhcrPlanner::stats() const {
  const double s = steps_ > 0 ? double(steps_) : 1.0;
  return {{"groups",
           {{"mean_count", group_count_sum_ / s},
            {"mean_size", group_count_sum_ ? double(agents_sum_) / group_count_sum_ : 0.0},
            {"mean_max_size", max_group_sum_ / s},
            {"replanned_per_step", replanned_groups_ / s},
            {"reused_per_step", reused_groups_ / s}}},
          {"cache_reuses", reused_groups_},
          {"primary_calls", primary_calls_},
          {"primary_time_mean_s", primary_calls_ ? primary_time_sum_ / primary_calls_ : 0.0},
          {"pbs_nodes", pbs_nodes_},
          {"soft_conflicts_in_plans", soft_conflicts_},
          {"threshold_fallbacks", threshold_fallbacks_},
          {"density_fallbacks", density_fallbacks_},
          {"budget_skips", budget_skips_},
          {"secondary_deadline_stops", pibt_.deadline_stops()},
          {"secondary_near_cuts", pibt_.near_cuts()},
          {"secondary_free_takes", pibt_.free_takes()},
          {"secondary_starts", pibt_.starts()},
          {"secondary_starts_won", pibt_.starts_won()},
          {"secondary_search_rounds", pibt_.search_rounds()},
          {"secondary_search_zoned_rounds", pibt_.zoned_rounds()},
          {"secondary_stalls", pibt_.stalls()},
          {"secondary_operation_calls", pibt_.operation_calls()},
          {"guidance_cut_short", guidance_ ? guidance_->cut_short() : 0},
          {"guidance_searches", guidance_ ? guidance_->searches() : 0},
          {"guidance_kept", guidance_ ? guidance_->kept() : 0},
          {"guidance_refined", guidance_ ? guidance_->refined() : 0},
          {"guidance_expansions", guidance_ ? guidance_->expansions() : 0},
          {"forecast_searches", forecast_ ? forecast_->searches() : 0},
          {"forecast_expansions", forecast_ ? forecast_->expansions() : 0},
          {"guidance_missed_share", guided_moves_ ? double(guidance_missed_) / guided_moves_ : 0.0},
          {"failure_fallbacks", failure_fallbacks_},
          {"timeouts", timeouts_},
          {"repairs", repairs_},
          {"steps_with_a_solve", solved_steps_},
          {"plan_time_mean_all_steps_s", plan_time_sum_all_steps_ / s}};
}

}  // namespace gdrhcr
