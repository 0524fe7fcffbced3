// RHCR with PBS and a PIBT fallback: see rhcr.hpp. Li et al., AAAI 2021.
#include "gdrhcr/rhcr.hpp"

#include <algorithm>

#include "gdrhcr/pbs.hpp"

namespace gdrhcr {

RhcrPlanner::RhcrPlanner(const Grid& grid, int num_agents, uint64_t seed, RhcrConfig config, ActionModel model)
    : seed_(seed), cfg_(config), model_(model), pibt_(grid, num_agents, seed, plain_pibt()) {
  if (cfg_.H < 1) throw ParamError("RHCR: H must be >= 1");
  if (cfg_.alpha < 1 || cfg_.alpha > cfg_.H) throw ParamError("RHCR: alpha must be in [1, H]");
  if (!(cfg_.timeout_s > 0)) throw ParamError("RHCR: timeout must be > 0");
  if (cfg_.node_budget < 0) throw ParamError("RHCR: node-budget must be >= 0");
}

bool RhcrPlanner::on_plan(const WorldView& world) const {
  const int k = world.timestep - plan_start_;
  const std::vector<uint8_t> immovable_at = world.taken_cell_mask();
  for (int i = 0; i < world.num_agents(); ++i) {
    const auto& p = plan_[i];
    if (!immovable_at.empty() && !world.is_immovable(i))
      for (size_t s = k + 1; s < p.size(); ++s)
        if (immovable_at[p[s]]) return false;  // runs into a robot that went offline since
    if (p[std::min<size_t>(k, p.size() - 1)] != world.positions[i]) return false;
    if (world.rotation() && plan_heads_[i][std::min<size_t>(k, p.size() - 1)] != (*world.headings)[i]) return false;
    // A robot that went offline after the plan was made cannot make its planned moves.
    if (world.is_immovable(i) && p[std::min<size_t>(k + 1, p.size() - 1)] != world.positions[i]) return false;
  }
  return true;
}

StepReport RhcrPlanner::plan_step(const WorldView& world, std::vector<Cell>& next) {
  check_action_model(name(), model_, world);
  const int n = world.num_agents();
  StepReport report;
  now_ = world.timestep;
  const bool period_over = !started_ || world.timestep - plan_start_ >= cfg_.alpha;
  bool replan = period_over;
  if (!replan && have_plan_ && !on_plan(world)) {
    replan = true;  // a robot lagged or was moved: the rest of the plan is stale
    ++deviation_replans_;
  }
  if (replan) {
    started_ = true;
    plan_start_ = world.timestep;
    // An agent without a known goal just keeps its cell (a one-goal sequence it already meets).
    // Immovable agents are not planned: their cells are blocked for everyone else.
    const std::vector<Cell> blocked = world.taken_cells();
    std::vector<int> movable;
    std::vector<Cell> starts;
    std::vector<std::vector<Cell>> goals;
    std::vector<Heading> headings;
    for (int i = 0; i < n; ++i) {
      if (world.is_immovable(i)) continue;
      movable.push_back(i);
      starts.push_back(world.positions[i]);
      headings.push_back(world.pose(i).heading);
      goals.push_back(world.goals[i].empty() ? std::vector<Cell>{world.positions[i]} : world.goals[i]);
    }
    PbsConfig pc;
    pc.horizon = cfg_.H;
    pc.c_soft = 0;
    pc.time_limit_s = cfg_.timeout_s;
    pc.node_budget = cfg_.node_budget;
    pc.blocked_cells = blocked.empty() ? nullptr : &blocked;
    pc.start_headings = world.rotation() ? &headings : nullptr;
    PbsResult r = solve_pbs(world.grid, world.dist, starts, goals, nullptr, pc);
    ++solver_calls_;
    nodes_ += r.nodes;
    sipp_calls_ += r.sipp_calls;
    solver_time_sum_ += r.time_s;
    solver_time_max_ = std::max(solver_time_max_, r.time_s);
    report = {true, r.time_s};
    have_plan_ = r.success;
    if (r.success) {
      plan_.assign(n, {});
      for (size_t k = 0; k < movable.size(); ++k) plan_[movable[k]] = std::move(r.paths[k]);
      for (int i = 0; i < n; ++i)
        if (world.is_immovable(i)) plan_[i].assign(cfg_.H + 1, world.positions[i]);
      plan_heads_.assign(n, {});
      for (size_t k = 0; world.rotation() && k < movable.size(); ++k) plan_heads_[movable[k]] = std::move(r.headings[k]);
      for (int i = 0; world.rotation() && i < n; ++i)
        if (world.is_immovable(i)) plan_heads_[i].assign(cfg_.H + 1, world.pose(i).heading);
    } else {
      ++solver_failures_;
      if (r.timed_out) ++timeouts_;
      plan_.clear();
    }
  }
  if (have_plan_) {
    const int k = world.timestep - plan_start_;
    for (int i = 0; i < n; ++i) next[i] = plan_[i][std::min<size_t>(k + 1, plan_[i].size() - 1)];
    for (int i = 0; world.rotation() && i < n; ++i)
      (*world.next_headings)[i] = plan_heads_[i][std::min<size_t>(k + 1, plan_heads_[i].size() - 1)];
  } else {
    pibt_.step(world, next);
    ++fallback_steps_;
  }
  return report;
}

std::vector<Cell> RhcrPlanner::planned_path(int agent) const {
  if (!have_plan_ || agent < 0 || agent >= static_cast<int>(plan_.size())) return {};
  const auto& path = plan_[agent];
  const size_t from = std::min<size_t>(std::max(0, now_ - plan_start_), path.size() - 1);
  return std::vector<Cell>(path.begin() + from, path.end());
}

nlohmann::json RhcrPlanner::params() const {
  return {{"H", cfg_.H},
          {"alpha", cfg_.alpha},
          {"timeout", cfg_.timeout_s},
          {"node_budget", cfg_.node_budget},
          {"solver", "pbs"},
          {"action_model", action_model_name(model_)},
          {"fallback", "pibt"},
          {"seed", seed_}};
}

nlohmann::json RhcrPlanner::stats() const {
  return {{"solver_calls", solver_calls_},
          {"solver_failures", solver_failures_},
          {"solver_timeouts", timeouts_},
          {"fallback_steps", fallback_steps_},
          {"deviation_replans", deviation_replans_},
          {"pbs_nodes", nodes_},
          {"sipp_calls", sipp_calls_},
          {"solver_time_mean_s", solver_calls_ ? solver_time_sum_ / solver_calls_ : 0.0},
          {"solver_time_max_s", solver_time_max_}};
}

}  // namespace gdrhcr
