// The PIBT planner (`--planner pibt`): PibtStep (pibt.hpp) over all agents every step, optionally
// following local guidance paths (local_guidance.hpp; after Arita & Okumura, "Lifelong LaCAM with
// Local Guidance", SoCS 2026) planned around the agents' motion forecast (motion_forecast.hpp).
#pragma once

#include <memory>
#include <vector>

#include "gdrhcr/local_guidance.hpp"
#include "gdrhcr/motion_forecast.hpp"
#include "gdrhcr/pibt.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr {

// PIBT over all agents, optionally following local guidance paths (local_guidance.hpp), planned
// around the agents' motion forecast when `forecast` has steps >= 2 (motion_forecast.hpp).
// In the rotation model (pibt.hpp) the guidance paths stay in cells (their distances from the
// rotation rows, least over headings); the next cell of an agent's path makes the action that
// goes or turns towards it PIBT's first choice.
class PibtPlanner : public Planner {
 public:
  PibtPlanner(const Grid& grid, int num_agents, uint64_t seed, PibtOptions options = {},
              const LocalGuidanceConfig* guidance = nullptr, const MotionForecastConfig* forecast = nullptr,
              ActionModel model = ActionModel::kMapf);
  ~PibtPlanner() override;
  std::string name() const override { return "pibt"; }
  StepReport plan_step(const WorldView& world, std::vector<Cell>& next) override;
  nlohmann::json params() const override;
  nlohmann::json stats() const override;
  std::vector<Cell> planned_path(int agent) const override;

 private:
  uint64_t seed_;
  ActionModel model_;
  PibtStep pibt_;
  std::unique_ptr<LocalGuidance> guidance_;
  std::unique_ptr<MotionForecast> forecast_;
  std::vector<int> order_;
  std::vector<Cell> preferred_;
  int now_ = 0;
};

}  // namespace gdrhcr
