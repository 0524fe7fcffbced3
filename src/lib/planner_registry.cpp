// One place that knows every planner by name; the command line and the ROS node both use it.
// Each planner is built from the values of the parameter table (planner_params.hpp), which
// holds every default, the product's and the paper preset's.
#include <stdexcept>
#include <utility>

#include "gdrhcr/gd_rhcr.hpp"
#include "gdrhcr/guided_pibt.hpp"
#include "gdrhcr/motion_forecast.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/planner_params.hpp"
#include "gdrhcr/rhcr.hpp"
#include "gdrhcr/window_lns.hpp"

namespace gdrhcr {
namespace {

PibtOptions pibt_options(const PlannerParams& v) {
  PibtOptions o;
  o.priority_reset = v.flag("priority-reset");
  o.swap = v.flag("swap");
  o.tie_break = v.text("tie-break") == "random" ? PibtOptions::TieBreak::kRandom : PibtOptions::TieBreak::kFreeFirst;
  const std::string rotation = v.text("rotation-pibt");
  o.rotation = rotation == "cells"  ? PibtOptions::Rotation::kCells
               : rotation == "auto" ? PibtOptions::Rotation::kAuto
                                    : PibtOptions::Rotation::kOperations;
  o.rotation_swap_wait = v.integer("rotation-swap-wait");
  o.rotation_commit = v.flag("rotation-commit");
  o.rotation_starts = v.integer("rotation-starts");
  o.rotation_keep = v.flag("rotation-keep");
  o.rotation_push_turn_cost = v.integer("rotation-push-turn-cost");
  o.dead_end_wait = v.integer("dead-end-wait");
  o.dead_end_parked = v.integer("dead-end-parked");
  return o;
}

LocalGuidanceConfig guidance_config(const PlannerParams& v, uint64_t seed) {
  LocalGuidanceConfig c;
  c.window = v.integer("lg-window");
  c.collision_cost = v.real("lg-cost");
  c.cost_per_kind = v.flag("lg-cost-per-kind");
  c.far_collision_cost = v.real("lg-far-cost");
  c.near_steps = v.integer("lg-near-steps");
  c.contraflow_cost = v.real("lg-contraflow");
  c.lazy = v.flag("lg-lazy");
  c.straight = v.flag("lg-straight");
  c.recheck = v.integer("lg-recheck");
  c.keep = v.integer("lg-keep");
  c.max_expansions = v.integer("lg-expansions");
  c.blocked_steps = v.integer("lg-blocked-steps");
  c.phases = v.integer("lg-phases");
  c.refine = v.integer("lg-refine");
  c.seed = seed;
  return c;
}

MotionForecastConfig forecast_config(const PlannerParams& v) {
  MotionForecastConfig c;
  c.steps = v.integer("lg-forecast");
  c.window = v.integer("lg-forecast-window");
  return c;
}

std::unique_ptr<Planner> make_pibt(const PlannerParams& v, const Grid& grid, int n, uint64_t seed, ActionModel m) {
  const PibtOptions o = pibt_options(v);
  if (v.text("guidance") != "local") return std::make_unique<PibtPlanner>(grid, n, seed, o, nullptr, nullptr, m);
  const LocalGuidanceConfig lg = guidance_config(v, seed);
  const MotionForecastConfig forecast = forecast_config(v);
  return std::make_unique<PibtPlanner>(grid, n, seed, o, &lg, &forecast, m);
}

std::unique_ptr<Planner> make_rhcr(const PlannerParams& v, const Grid& grid, int n, uint64_t seed, ActionModel m) {
  RhcrConfig c;
  c.H = v.integer("H");
  c.alpha = v.integer("alpha");
  c.timeout_s = v.real("timeout");
  c.node_budget = v.integer("node-budget");
  return std::make_unique<RhcrPlanner>(grid, n, seed, c, m);
}

std::unique_ptr<Planner> make_gd_rhcr(const PlannerParams& v, const Grid& grid, int n, uint64_t seed, ActionModel m) {
  auto planner = std::make_unique<GdRhcrPlanner>(grid, n, seed, gd_rhcr_config(v, seed), m);
  if (v.integer("lns-window") <= 0) return planner;
  WindowLnsConfig c;
  c.window = v.integer("lns-window");
  c.neighbourhood = v.integer("lns-neighbours");
  c.iterations = v.integer("lns-iterations");
  c.step_budget_s = v.real("step-budget");
  c.threads = v.integer("threads");
  c.seed = seed;
  PibtOptions rollout = pibt_options(v);
  rollout.rotation = PibtOptions::Rotation::kCells;
  rollout.rotation_commit = false;
  rollout.rotation_starts = 1;
  return std::make_unique<WindowLns>(std::move(planner), grid, n, c, rollout, m);
}

using Factory = std::unique_ptr<Planner> (*)(const PlannerParams&, const Grid&, int, uint64_t, ActionModel);
struct Entry {
  std::string name;
  Factory factory;
  bool rotation;  // plans in the rotation action model
};
const std::vector<Entry>& registry() {
  static const std::vector<Entry> planners = {
      {"pibt", make_pibt, true}, {"rhcr", make_rhcr, true}, {"gd-rhcr", make_gd_rhcr, true}};
  return planners;
}

}  // namespace

GdRhcrConfig gd_rhcr_config(const PlannerParams& v, uint64_t seed) {
  GdRhcrConfig c;
  c.V = v.integer("V");
  c.H = v.integer("H");
  c.c_soft = v.real("c-soft");
  c.k_threshold = v.integer("k-threshold");
  c.timeout_s = v.real("timeout");
  c.step_budget_s = v.real("step-budget");
  c.node_budget = v.integer("node-budget");
  c.threads = v.integer("threads");
  c.solver = v.text("solver");
  c.max_density = v.real("max-density");
  c.density_margin = v.integer("density-margin");
  c.pibt = pibt_options(v);
  c.pibt.search_threads = c.threads;
  c.guidance = v.text("guidance") == "local";
  c.forecast = forecast_config(v);
  c.lg = guidance_config(v, seed);
  return c;
}

std::vector<std::string> planner_names() {
  std::vector<std::string> names;
  for (auto& e : registry()) names.push_back(e.name);
  return names;
}

bool planner_supports(const std::string& name, ActionModel model) {
  for (auto& e : registry())
    if (e.name == name) return model == ActionModel::kMapf || e.rotation;
  return false;
}

void check_action_model(const std::string& planner, ActionModel built, const WorldView& world) {
  if (world.action_model != built)
    throw std::invalid_argument("planner " + planner + " was built for the " + action_model_name(built) +
                                " action model but asked to plan in the " + action_model_name(world.action_model) +
                                " model");
  if (world.rotation() && (!world.headings || !world.next_headings))
    throw std::invalid_argument("planner " + planner + ": the rotation model needs headings and next_headings");
}

std::unique_ptr<Planner> make_planner(const PlannerParams& values, const Grid& grid, int num_agents,
                                      uint64_t seed, ActionModel model) {
  for (auto& e : registry()) {
    if (e.name != values.planner()) continue;
    if (!planner_supports(e.name, model))
      throw ParamError("planner '" + e.name + "' does not plan in the " + action_model_name(model) +
                       " action model (yet); use --action-model mapf or another planner");
    return e.factory(values, grid, num_agents, seed, model);
  }
  throw ParamError("unknown planner '" + values.planner() + "'");
}

std::unique_ptr<Planner> make_planner(const std::string& name, Params& params, const Grid& grid,
                                      int num_agents, uint64_t seed, ActionModel model) {
  const PlannerParams values = PlannerParams::resolve(name, params, MapFacts(grid, num_agents, model));
  params.check_all_used("planner " + name);
  return make_planner(values, grid, num_agents, seed, model);
}

}  // namespace gdrhcr
