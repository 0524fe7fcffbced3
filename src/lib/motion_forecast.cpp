#include "gdrhcr/motion_forecast.hpp"

#include <algorithm>
#include <functional>

namespace gdrhcr {

namespace {
Cell goal_of(const WorldView& world, int i) {
  return world.goals[i].empty() ? world.positions[i] : world.goals[i][0];
}

// The rollout guidance: the real one's costs, a shorter window, and paths kept lazily: until the
// agent leaves its path, the path runs out, or it meets another within kRecheck steps.
constexpr int kRecheck = 3;

LocalGuidanceConfig rollout_guidance(const MotionForecastConfig& f, LocalGuidanceConfig c) {
  c.window = f.window;
  c.lazy = true;
  c.recheck = kRecheck;
  c.keep = 0;
  c.phases = 0;
  return c;
}
}  // namespace

MotionForecast::MotionForecast(const Grid& grid, int num_agents, MotionForecastConfig config,
                               const LocalGuidanceConfig& guidance)
    : cfg_(config),
      path_(num_agents),
      goal_(num_agents, kNoCell),
      guide_(std::make_unique<LocalGuidance>(grid, num_agents, rollout_guidance(config, guidance))) {
  if (cfg_.window < 1) throw ParamError("motion forecast: window must be >= 1");
}

MotionForecast::~MotionForecast() = default;

// The rollout guidance at world.timestep + 1: the rolled agents' guidance paths from then on
// (kept by the lazy rule, replanned when they meet another soon or were left), the others'
// given cells as obstacles (never replanned), nothing for the rest.
void MotionForecast::start_rollout(const WorldView& world, const LocalGuidance& guidance,
                                   const std::vector<std::vector<Cell>>* fixed) {
  const int t1 = world.timestep + 1;
  for (int j = 0; j < world.num_agents(); ++j) {
    std::vector<Cell> p;
    if (in_set_[j]) p = guidance.path_from(j, t1);
    else if (fixed && !(*fixed)[j].empty()) p = (*fixed)[j];
    if (!p.empty() && p[0] == pos_[j]) guide_->set_path(j, t1, p, in_set_[j] ? goal_of(world, j) : kNoCell);
    else guide_->clear(j);
  }
}

// Moves of the agents outside the rollout from world.timestep + k to + k + 1: their given cells,
// or staying at their next cell. PIBT keeps the rolled agents clear of them.
void MotionForecast::fix_others(int k, const std::vector<Cell>& next, const std::vector<std::vector<Cell>>* fixed) {
  fixed_moves_.clear();
  for (int j = 0; j < static_cast<int>(in_set_.size()); ++j) {
    if (in_set_[j]) continue;
    Cell from = next[j], to = next[j];
    if (fixed && !(*fixed)[j].empty()) {
      const auto& f = (*fixed)[j];
      from = f[std::min<size_t>(k - 1, f.size() - 1)];
      to = f[std::min<size_t>(k, f.size() - 1)];
    }
    pos_[j] = from;
    fixed_moves_.emplace_back(from, to);
  }
}

void MotionForecast::roll(const WorldView& world, const std::vector<Cell>& next,
                          const std::vector<int>& agents, const PibtStep& pibt,
                          const LocalGuidance& guidance, const std::vector<std::vector<Cell>>* fixed,
                          std::chrono::steady_clock::time_point deadline) {
  const int n = world.num_agents();
  path_.resize(n);
  goal_.resize(n, kNoCell);
  for (auto& p : path_) p.clear();
  start_ = world.timestep + 1;
  for (int i : agents) {
    path_[i].reserve(cfg_.steps);
    path_[i].push_back(next[i]);
    goal_[i] = goal_of(world, i);
  }
  if (cfg_.steps < 2 || agents.empty()) return;
  pibt_.reset();
  pibt_.emplace(pibt);  // the rollout must not advance the real PIBT's priorities or random numbers
  in_set_.assign(n, 0);
  for (int i : agents) in_set_[i] = 1;
  pos_ = next;
  if (world.rotation()) heads_ = *world.next_headings, next_heads_ = heads_;
  moves_.assign(n, kNoCell);
  preferred_.assign(n, kNoCell);
  start_rollout(world, guidance, fixed);
  const bool timed = deadline != std::chrono::steady_clock::time_point::max();
  for (int k = 1; k < cfg_.steps; ++k) {
    if (timed && std::chrono::steady_clock::now() >= deadline) break;
    const int t = world.timestep + k;
    fix_others(k, next, fixed);
    WorldView view{world.grid, world.dist, t, pos_, world.goals, world.immovable, world.blocked};
    if (world.rotation()) {
      view.action_model = ActionModel::kRotation;
      view.headings = &heads_;
      view.next_headings = &next_heads_;
    }
    order_ = agents;  // guidance in priority order, as the real update
    std::stable_sort(order_.begin(), order_.end(),
                     [&](int a, int b) { return pibt_->priority(a) > pibt_->priority(b); });
    guide_->update(view, order_, deadline);
    for (int i : agents)
      preferred_[i] = world.rotation() ? guide_->next_move(i, t, pos_[i]) : guide_->next_cell(i, t, pos_[i]);
    pibt_->step(view, moves_, agents, fixed_moves_, &preferred_);
    for (int i : agents) pos_[i] = moves_[i], path_[i].push_back(moves_[i]);
    if (world.rotation())
      for (int i : agents) heads_[i] = next_heads_[i];
  }
}

void MotionForecast::seed(const WorldView& world, const std::vector<int>& agents, LocalGuidance& guidance) const {
  const int off = world.timestep - start_;
  if (start_ < 0 || off < 0) return;
  std::vector<Cell> rest;
  for (int i : agents) {
    if (i >= static_cast<int>(path_.size()) || static_cast<int>(path_[i].size()) <= off) continue;
    if (goal_[i] != goal_of(world, i)) {  // a new goal: the old way says nothing about it
      guidance.clear(i);
      continue;
    }
    if (path_[i][off] != world.positions[i]) continue;
    rest.assign(path_[i].begin() + off, path_[i].end());
    // A forecast that never moves is not used: planned around as a parked agent, it keeps the
    // agent parked (random-32-32-20: an agent waited 311 steps); its own last path stays.
    if (std::adjacent_find(rest.begin(), rest.end(), std::not_equal_to<Cell>()) == rest.end()) continue;
    guidance.set_path(i, world.timestep, rest);
  }
}

}  // namespace gdrhcr
