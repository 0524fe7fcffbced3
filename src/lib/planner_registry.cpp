// One place that knows every planner by name; the command line and the ROS node both use it.
#include <stdexcept>
#include <utility>

#include "gdrhcr/cut_cells.hpp"
#include "gdrhcr/gd_rhcr.hpp"
#include "gdrhcr/motion_forecast.hpp"
#include "gdrhcr/pibt.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/rhcr.hpp"

namespace gdrhcr {
namespace {

// `--preset paper` selects the paper's exact configuration (PBS + plain PIBT for GD-RHCR, plain
// PIBT for the PIBT baseline); `default` (or no preset) the product's stronger one. Explicit
// parameters override either.
bool paper_preset(Params& p) { return p.get_choice("preset", "default", {"default", "paper"}) == "paper"; }

// PIBT's techniques, each switchable for ablations. Plain PIBT (the paper's) has no swap.
PibtOptions pibt_options(Params& p, bool paper) {
  PibtOptions o;
  o.priority_reset = p.get_int("priority-reset", 1, 0, 1) == 1;
  o.swap = p.get_int("swap", paper ? 0 : 1, 0, 1) == 1;
  const std::string tie = p.get_choice("tie-break", "free-first", {"free-first", "random", "hindrance"});
  o.tie_break = tie == "random"      ? PibtOptions::TieBreak::kRandom
                : tie == "hindrance" ? PibtOptions::TieBreak::kHindrance
                                     : PibtOptions::TieBreak::kFreeFirst;
  return o;
}

// Guidance replanned every step costs about one small search per agent per step; past
// kLazyGuidanceAgents agents the default keeps paths lazily instead (fleets of 10,000), and
// updates them in two phases of map bands on the thread pool (local_guidance.hpp).
constexpr int kLazyGuidanceAgents = 2000;

// With the motion forecast, conflicts near_steps (3) or more steps ahead cost kFarCollisionCost (issue 11,
// session 7: random-32-32-20 300 +1.3% over seeds 1-10, random-64-64-20 800 and room-64-64-8 400
// +1%; on warehouses without the forecast it loses 1.6-2%, so it goes with the forecast).
constexpr double kFarCollisionCost = 2.0;

// The product default's contraflow cost (local_guidance.hpp; issue 11, session 8). Seeds 1-5
// against none, 0.1 / 0.2: warehouse-10-20-10-2-1 400 +1.0% / +0.7%, 800 +3.7% / +4.5%, MAPD 800
// +2.8% / +2.7%; random-32-32-20 300 +2.8% / +3.1%, 200 +1.7% / +1.9%; random-64-64-20 800
// +1.7% / +1.7%; room-32-32-4 200 +4.3% / +4.7%; room-64-64-8 400 +5.8% / +4.6%;
// warehouse-10-20-10-2-2 800 +0.3% / +0.2%; empty-48-48 400 -0.02% / -0.1%. 0.1 for its lower
// cost (about 15% more guidance expansions than none) and the open maps.
constexpr double kContraflowCost = 0.1;

LocalGuidanceConfig guidance_config(Params& p, int num_agents, int default_window = LocalGuidanceConfig{}.window,
                                    bool with_forecast = false, double default_contraflow = 0) {
  LocalGuidanceConfig c;
  c.window = p.get_int("lg-window", default_window, 1, 1000);
  // Lazy paths are searched again only when they meet another one; a cheaper collision lets
  // them meet (and be searched) more often: 10,000 agents on warehouse-20-40-10-2-2, 300 steps,
  // throughput 32.31 -> 35.13 (1.23x -> 1.34x PIBT) for ~25% more CPU (docs/results.md).
  c.collision_cost = p.get_double("lg-cost", num_agents > kLazyGuidanceAgents ? 1.5 : c.collision_cost, 0.0, 1e6);
  // Per kind of conflict (vertex, swap) (issue 11, session 7: random-32-32-20 300 +1.3%,
  // warehouse-10-20-10-2-1 800 +1.9%, seeds 1-5 / 1-3; warehouse-20-40-10-2-2 2,500 / 5,000
  // agents +0.4% / -0.1% for 7% / 13% less CPU).
  c.cost_per_kind = p.get_int("lg-cost-per-kind", 1, 0, 1) == 1;
  c.far_collision_cost = p.get_double("lg-far-cost", with_forecast ? kFarCollisionCost : -1, -1, 1e6);
  if (c.far_collision_cost < 0 && c.far_collision_cost != -1)
    throw ParamError("parameter lg-far-cost must be >= 0, or -1 (as lg-cost)");
  c.near_steps = p.get_int("lg-near-steps", c.near_steps, 0, 1000);
  c.contraflow_cost = p.get_double("lg-contraflow", default_contraflow, 0.0, 1e6);
  c.lazy = p.get_int("lg-lazy", num_agents > kLazyGuidanceAgents ? 1 : 0, 0, 1) == 1;
  c.recheck = p.get_int("lg-recheck", c.recheck, 0, 1000);
  c.keep = p.get_int("lg-keep", c.keep, -1, 1000);
  c.keep_optimal = p.get_int("lg-keep-optimal", c.keep_optimal ? 1 : 0, 0, 1) == 1;
  c.max_expansions = p.get_int("lg-expansions", c.max_expansions, 1, 1 << 30);
  c.refresh = p.get_int("lg-refresh", c.refresh, 0, 1 << 20);
  c.blocked_steps = p.get_int("lg-blocked-steps", c.blocked_steps, -1, 1000);
  c.phases = p.get_int("lg-phases", num_agents > kLazyGuidanceAgents ? 2 : 0, 0, 1000);
  if (c.phases == 1) throw ParamError("parameter lg-phases must be 0 (sequential) or >= 2");
  return c;
}

// Maps where at least 1% of the free cells are cut cells (dead ends, one-lane passages:
// random-32-32-20 2.8%, random-64-64-20 3.3%, room-64-64-8 1.8%; warehouses and open maps none).
bool many_cut_cells(const Grid& grid) { return cut_cell_share(grid) >= 0.01; }

// The product default's motion forecast: 8 steps, rollout window 8 (as good as 10 and 10 on
// random-32-32-20 over seeds 1-3 and about 15% cheaper) on maps where at least 1% of the free cells
// are cut cells (dead ends, one-lane passages: random-32-32-20 has 2.8%), where agents' real
// motion strays from their guidance (backing out of dead ends, swaps) and guidance planned around
// the forecast gains 5-8% (docs/results.md, issue 11); none on biconnected maps (warehouses, open
// maps: no gain there, for twice the CPU) and none past kLazyGuidanceAgents agents.
int default_forecast_steps(const Grid& grid, int num_agents) {
  if (num_agents > kLazyGuidanceAgents) return 0;
  return many_cut_cells(grid) ? 8 : 0;
}

// The product default's guidance window: 30 steps on maps without many cut cells, up to
// kLazyGuidanceAgents agents (issue 11, seeds 1-3 against 20: warehouse-10-20-10-2-1 400 / 800
// agents +0.6% / +1.7%, warehouse-10-20-10-2-2 800 +0.4%, empty-48-48 400 +0.2%, for 20-40% more
// CPU on the warehouses, where paths are long and head-on meetings in an aisle show up more than
// 20 steps ahead); else 20: where the motion forecast runs (random-32-32-20 300: 30 gains nothing;
// room-64-64-8 400: twice the CPU, its doors make detours long) and for fleets of thousands.
int default_guidance_window(const Grid& grid, int num_agents) {
  return num_agents > kLazyGuidanceAgents || many_cut_cells(grid) ? 20 : 30;
}

// The motion forecast the guidance is planned around (motion_forecast.hpp): `lg-forecast` steps
// (0 = none), rolled with a guidance of window `lg-forecast-window`.
MotionForecastConfig forecast_config(Params& p, int default_steps) {
  MotionForecastConfig c;
  c.steps = p.get_int("lg-forecast", default_steps, 0, 1000);
  if (c.steps == 1) throw ParamError("parameter lg-forecast must be 0 (none) or >= 2");
  c.window = p.get_int("lg-forecast-window", c.window, 1, 1000);
  return c;
}

const std::vector<std::pair<std::string, PlannerFactory>>& registry() {
  static const std::vector<std::pair<std::string, PlannerFactory>> planners = {
      {"pibt",
       [](Params& p, const Grid& grid, int n, uint64_t seed) -> std::unique_ptr<Planner> {
         const PibtOptions o = pibt_options(p, paper_preset(p));
         if (p.get_choice("guidance", "none", {"none", "local"}) == "local") {
           const MotionForecastConfig forecast = forecast_config(p, 0);
           LocalGuidanceConfig lg = guidance_config(p, n, LocalGuidanceConfig{}.window, forecast.steps >= 2);
           lg.seed = seed;
           return std::make_unique<PibtPlanner>(grid, n, seed, o, &lg, &forecast);
         }
         return std::make_unique<PibtPlanner>(grid, n, seed, o);
       }},
      {"rhcr",
       [](Params& p, const Grid& grid, int n, uint64_t seed) -> std::unique_ptr<Planner> {
         RhcrConfig c;
         c.H = p.get_int("H", c.H, 1, 100000);
         c.alpha = p.get_int("alpha", c.alpha, 1, 100000);
         if (c.alpha > c.H) throw ParamError("parameter alpha must be <= H (" + std::to_string(c.H) + ")");
         c.timeout_s = p.get_double("timeout", c.timeout_s, 0, 1e9);
         if (!(c.timeout_s > 0)) throw ParamError("parameter timeout must be > 0 seconds");
         c.node_budget = p.get_int("node-budget", 0, 0, 2000000000);
         return std::make_unique<RhcrPlanner>(grid, n, seed, c);
       }},
      {"gd-rhcr",
       [](Params& p, const Grid& grid, int n, uint64_t seed) -> std::unique_ptr<Planner> {
         const bool paper = paper_preset(p);
         GdRhcrConfig c = paper ? GdRhcrConfig::paper() : GdRhcrConfig::product();
         c.V = p.get_int("V", c.V, 0, 1 << 20);
         c.H = p.get_int("H", c.H, 1, 100000);
         c.c_soft = p.get_double("c-soft", c.c_soft, 0.0, 1e9);
         c.k_threshold = p.get_int("k-threshold", 0, 1, 1 << 30);
         c.timeout_s = p.get_double("timeout", c.timeout_s, 0, 1e9);
         if (!(c.timeout_s > 0)) throw ParamError("parameter timeout must be > 0 seconds");
         c.step_budget_s = p.get_double("step-budget", 0, 0, 1e6);
         c.node_budget = p.get_int("node-budget", 0, 0, 2000000000);
         c.threads = p.get_int("threads", c.threads, 1, 1024);
         c.solver = p.get_choice("solver", c.solver, {"pbs", "pibt"});
         c.solver2 = p.get_choice("solver2", c.solver2, {"pibt"});
         c.max_density = p.get_double("max-density", c.max_density, 0.0, 1.0);
         c.density_margin = p.get_int("density-margin", c.density_margin, 0, 1 << 20);
         c.secondary_stay = p.get_int("secondary-stay", c.secondary_stay, 0, 1 << 20);
         c.pibt = pibt_options(p, paper);  // the preset's PIBT unless overridden
         c.guidance = p.get_choice("guidance", c.guidance ? "local" : "none", {"none", "local"}) == "local";
         c.forecast = forecast_config(p, paper ? 0 : default_forecast_steps(grid, n));
         c.lg = guidance_config(p, n, paper ? LocalGuidanceConfig{}.window : default_guidance_window(grid, n),
                                c.guidance && c.forecast.steps >= 2, paper ? 0 : kContraflowCost);
         c.lg.seed = seed;
         return std::make_unique<GdRhcrPlanner>(grid, n, seed, c);
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
