// One place that knows every planner by name; the command line and the ROS node both use it.
#include <stdexcept>
#include <utility>

#include "gdrhcr/pibt.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr {
namespace {

const std::vector<std::pair<std::string, PlannerFactory>>& registry() {
  static const std::vector<std::pair<std::string, PlannerFactory>> planners = {
      {"pibt",
       [](Params&, const Grid& grid, int n, uint64_t seed) -> std::unique_ptr<Planner> {
         return std::make_unique<PibtPlanner>(grid, n, seed);
       }},
  };
  return planners;
}

}  // namespace

std::vector<std::string> planner_names() {
  std::vector<std::string> names;
  for (auto& [name, f] : registry()) names.push_back(name);
  return names;
}

std::unique_ptr<Planner> make_planner(const std::string& name, Params& params, const Grid& grid,
                                      int num_agents, uint64_t seed) {
  for (auto& [n, factory] : registry())
    if (n == name) return factory(params, grid, num_agents, seed);
  std::string all;
  for (auto& n : planner_names()) all += (all.empty() ? "" : ", ") + n;
  throw ParamError("unknown planner '" + name + "' (known: " + all + ")");
}

}  // namespace gdrhcr
