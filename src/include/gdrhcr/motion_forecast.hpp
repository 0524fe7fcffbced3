// Motion forecast: where the agents will really be over the next steps, as the paths that the
// next local-guidance update plans around.
// Idea after Arita & Okumura, "Lifelong LaCAM with Local Guidance" (SoCS 2026). Their lifelong
// runner starts each step's guidance from the previous step's horizon plan: the configurations
// its LaCAM search went through, each made by PIBT following guidance replanned at that
// configuration. Measured on their code (docs/results.md, issue 11), the executed step is always
// the root's PIBT configuration; what the horizon buys is that seed. Guidance planned around a
// forecast of the others' real motion (queued, pushed aside, waiting) beats guidance planned
// around their wishes (their last guidance paths), which are not collision-free among themselves.
//
// Here, after a step is decided, the agents are rolled `steps` - 1 more steps forward by a copy
// of the step's PIBT (priorities, swap, tie-breaks) following a rollout guidance of its own,
// with a shorter window, that starts from the step's guidance paths and replans a path lazily:
// when the agent left it, it ran out, or it meets another path within the next 3 steps. (Not
// replanning paths that meet others, i.e. following the step's guidance, forecasts badly: see
// docs/results.md.) At the next step, before the real guidance update, every agent that stands
// where the forecast says and still has the same goal gets the rest of its forecast as its path
// in the guidance table, unless the forecast never moves (planned around as parked, a parked
// agent stays parked: it keeps its last path); agents with a new goal get none. The update then
// replans every agent in priority order as usual, each against the new paths of the agents
// before it and the forecasts of those after it. In the rotation model the rollout carries the
// agents' headings from the step's next headings (WorldView::next_headings) and its PIBT copy
// plans in that model.
#pragma once

#include <chrono>
#include <memory>
#include <optional>
#include <vector>

#include "gdrhcr/local_guidance.hpp"
#include "gdrhcr/pibt.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr {

struct MotionForecastConfig {
  int steps = 0;    // forecast length counting the decided step; < 2 = no forecast
  int window = 8;   // the rollout guidance's window
};

class MotionForecast {
 public:
  // `guidance` is the real guidance's configuration (collision cost, expansions, seed).
  MotionForecast(const Grid& grid, int num_agents, MotionForecastConfig config,
                 const LocalGuidanceConfig& guidance);
  ~MotionForecast();

  // Rolls `agents` forward from `next` (their cells at world.timestep + 1) with a copy of `pibt`,
  // starting from the paths of `guidance`. `fixed` (optional) gives, per agent outside `agents`,
  // its cells from world.timestep + 1 on (empty: it stays at its next cell). Past `deadline` the
  // rollout stops: the forecast is shorter. The rollout's guidance refines as the real one does
  // (lg-refine; by default only with a deadline), until `deadline`.
  void roll(const WorldView& world, const std::vector<Cell>& next, const std::vector<int>& agents,
            const PibtStep& pibt, const LocalGuidance& guidance,
            const std::vector<std::vector<Cell>>* fixed = nullptr,
            std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max());

  // Before the guidance update of a later step: `agents` that stand where their forecast says,
  // with the goal it was made for, get the rest of it as their path in `guidance` if it moves at
  // all; those whose goal changed get no path. Others keep what they have.
  void seed(const WorldView& world, const std::vector<int>& agents, LocalGuidance& guidance) const;

  // Agent i's forecast cells from the last roll's world.timestep + 1 on (empty when none).
  const std::vector<Cell>& forecast(int i) const { return path_[i]; }
  const MotionForecastConfig& config() const { return cfg_; }
  // The rollout guidance's searches and their expansions so far.
  long searches() const { return guide_->searches(); }
  long expansions() const { return guide_->expansions(); }

 private:
  void start_rollout(const WorldView& world, const LocalGuidance& guidance,
                     const std::vector<std::vector<Cell>>* fixed);
  void fix_others(int k, const std::vector<Cell>& next, const std::vector<std::vector<Cell>>* fixed);

  MotionForecastConfig cfg_;
  int start_ = -1;                       // the timestep of each forecast's first cell
  std::vector<std::vector<Cell>> path_;  // per agent
  std::vector<Cell> goal_;               // the goal each forecast was made for
  std::unique_ptr<LocalGuidance> guide_;  // the rollout's guidance
  std::optional<PibtStep> pibt_;          // the rollout's copy of the step's PIBT
  std::vector<uint8_t> in_set_;
  std::vector<int> order_;
  std::vector<Cell> pos_, moves_, preferred_;
  std::vector<Heading> heads_, next_heads_;  // rotation: the rollout's headings
  std::vector<std::pair<Cell, Cell>> fixed_moves_;
};

}  // namespace gdrhcr
