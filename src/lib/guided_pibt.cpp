#include "gdrhcr/guided_pibt.hpp"

#include <algorithm>
#include <chrono>
#include <numeric>

#include "gdrhcr/motion_forecast.hpp"

namespace gdrhcr {

PibtPlanner::PibtPlanner(const Grid& grid, int num_agents, uint64_t seed, PibtOptions options,
                         const LocalGuidanceConfig* guidance, const MotionForecastConfig* forecast,
                         ActionModel model)
    : seed_(seed), model_(model), pibt_(grid, num_agents, seed, options) {
  if (guidance) guidance_ = std::make_unique<LocalGuidance>(grid, num_agents, *guidance);
  if (guidance && forecast && forecast->steps >= 2)
    forecast_ = std::make_unique<MotionForecast>(grid, num_agents, *forecast, *guidance);
}

PibtPlanner::~PibtPlanner() = default;

nlohmann::json PibtPlanner::params() const {
  const auto& o = pibt_.options();
  nlohmann::json p = {{"seed", seed_},
                      {"action_model", action_model_name(model_)},
                      {"priority_reset", o.priority_reset},
                      {"swap", o.swap},
                      {"tie_break", o.tie_break == PibtOptions::TieBreak::kFreeFirst ? "free-first" : "random"},
                      {"rotation_pibt", PibtOptions::name(o.rotation)},
                      {"guidance", guidance_ ? "local" : "none"}};
  if (guidance_) {
    p["lg_window"] = guidance_->config().window;
    p["lg_cost"] = guidance_->config().collision_cost;
    p["lg_cost_per_kind"] = guidance_->config().cost_per_kind;
    p["lg_far_cost"] = guidance_->config().far_collision_cost;
    p["lg_near_steps"] = guidance_->config().near_steps;
    p["lg_contraflow"] = guidance_->config().contraflow_cost;
    p["lg_lazy"] = guidance_->config().lazy;
    p["lg_straight"] = guidance_->config().straight;
    p["lg_phases"] = guidance_->config().phases;
    p["lg_forecast"] = forecast_ ? forecast_->config().steps : 0;
    if (forecast_) p["lg_forecast_window"] = forecast_->config().window;
  }
  return p;
}

nlohmann::json PibtPlanner::stats() const {
  nlohmann::json s = {{"swaps", pibt_.swaps()}};
  if (guidance_) s["guidance_searches"] = guidance_->searches(), s["guidance_expansions"] = guidance_->expansions();
  return s;
}

std::vector<Cell> PibtPlanner::planned_path(int agent) const {
  return guidance_ ? guidance_->path_from(agent, now_) : std::vector<Cell>{};
}

StepReport PibtPlanner::plan_step(const WorldView& world, std::vector<Cell>& next) {
  check_action_model(name(), model_, world);
  const auto t0 = std::chrono::steady_clock::now();
  now_ = world.timestep;
  if (guidance_) {
    const int n = world.num_agents();
    order_.resize(n);
    std::iota(order_.begin(), order_.end(), 0);
    // Higher-priority agents plan their guidance first, so theirs is the least disturbed.
    std::stable_sort(order_.begin(), order_.end(),
                     [&](int a, int b) { return pibt_.priority(a) > pibt_.priority(b); });
    if (forecast_) forecast_->seed(world, order_, *guidance_);
    guidance_->update(world, order_);
    preferred_.resize(n);
    for (int i = 0; i < n; ++i)
      preferred_[i] = world.rotation() ? guidance_->next_move(i, now_, world.positions[i])
                                       : guidance_->next_cell(i, now_, world.positions[i]);
    pibt_.step(world, next, {}, {}, &preferred_);
    if (forecast_) forecast_->roll(world, next, order_, pibt_, *guidance_);
  } else {
    pibt_.step(world, next);
  }
  return {true, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
}

}  // namespace gdrhcr
