#include "gdrhcr/map_prep.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>

#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/planner_params.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/task_stream.hpp"

namespace gdrhcr {

namespace {

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

// One trial of `steps` steps, cut short at wall_limit_s (> 0); PrepTrial::steps says how many ran.
PrepTrial run_trial(const Grid& grid, const PrepOptions& o, double traffic_cost, uint64_t seed, int steps,
                    double wall_limit_s = 0) {
  Params given = o.given;
  given.set("traffic-cost", number(traffic_cost));
  if (o.step_budget_s > 0 && planner_has_param(o.planner, "step-budget") && !given.has("step-budget"))
    given.set("step-budget", number(o.step_budget_s));
  const PlannerParams values = PlannerParams::resolve(o.planner, given, MapFacts(grid, o.agents, o.model));
  given.check_all_used("preparation: planner " + o.planner);
  const DistTable dist(grid, o.model, size_t(o.dist_budget_mb) << 20, step_costs(values, o.model));
  RandomNavigationStream tasks(grid, seed);
  const auto planner = make_planner(values, grid, o.agents, seed, o.model);
  SimOptions sim;
  sim.steps = steps;
  sim.action_model = o.model;
  sim.wall_limit_s = wall_limit_s;
  sim.free_flow = false;
  const auto start = std::chrono::steady_clock::now();
  const SimResult r = run_simulation(grid, dist, tasks, *planner, random_starts(grid, o.agents, seed), sim);
  const std::chrono::duration<double> took = std::chrono::steady_clock::now() - start;
  return {traffic_cost, seed, r.goals_reached, took.count(), r.steps};
}

}  // namespace

std::string map_key(const Grid& grid) {
  uint64_t h = 1469598103934665603ull;
  auto mix = [&h](uint64_t v) {
    for (int b = 0; b < 8; ++b) h = (h ^ ((v >> (8 * b)) & 0xff)) * 1099511628211ull;
  };
  mix(uint64_t(grid.width()));
  mix(uint64_t(grid.height()));
  for (Cell c : grid.free_cells()) mix(uint64_t(c));
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

MapPrep prepare_map(const Grid& grid, const PrepOptions& o) {
  if (o.model != ActionModel::kRotation)
    throw ParamError("offline preparation chooses the traffic cost, which applies to the rotation model only");
  if (o.agents < 1 || o.agents > int(grid.free_cells().size()))
    throw ParamError("offline preparation: agents must be in [1, " + std::to_string(grid.free_cells().size()) +
                     "], not " + std::to_string(o.agents));
  if (o.steps < 1) throw ParamError("offline preparation: steps must be >= 1");
  if (o.seeds < 1) throw ParamError("offline preparation: seeds must be >= 1");
  if (o.traffic_costs.empty()) throw ParamError("offline preparation: no candidate traffic cost");
  MapPrep p;
  p.map_key = map_key(grid);
  p.width = grid.width(), p.height = grid.height(), p.agents = o.agents;
  p.model = o.model, p.planner = o.planner, p.step_budget_s = o.step_budget_s, p.seed = o.seed;
  p.seeds = o.seeds;
  const std::vector<double>& candidates = o.traffic_costs;
  // With a time limit the first trial runs for its share of it, and the others as many steps.
  const double share = o.time_limit_s > 0 ? o.time_limit_s / (double(candidates.size()) * o.seeds) : 0;
  p.trials.push_back(run_trial(grid, o, candidates.front(), o.seed, o.steps, share));
  p.steps = std::max(1, p.trials.front().steps);
  for (size_t c = 0; c < candidates.size(); ++c)
    for (int s = 0; s < o.seeds; ++s)
      if (c > 0 || s > 0) p.trials.push_back(run_trial(grid, o, candidates[c], o.seed + uint64_t(s), p.steps));
  const long first = p.goals_of(candidates.front());
  p.traffic_cost = candidates.front();
  for (double k : candidates)
    if (p.goals_of(k) > p.goals_of(p.traffic_cost) && p.goals_of(k) > (1 + MapPrep::kMargin) * first)
      p.traffic_cost = k;
  return p;
}

long MapPrep::goals_of(double k) const {
  long goals = 0;
  for (auto& t : trials) goals += t.traffic_cost == k ? t.goals : 0;
  return goals;
}

nlohmann::json MapPrep::to_json() const {
  nlohmann::json trials = nlohmann::json::array();
  for (auto& t : this->trials)
    trials.push_back({{"traffic_cost", t.traffic_cost}, {"seed", t.seed}, {"goals", t.goals}, {"seconds", t.seconds}});
  return {{"format", kFormat}, {"map_key", map_key},   {"width", width},
          {"height", height},  {"agents", agents},     {"action_model", action_model_name(model)},
          {"planner", planner}, {"steps", steps},      {"step_budget_s", step_budget_s},
          {"seed", seed},      {"seeds", seeds},       {"trials", trials},
          {"traffic_cost", traffic_cost}};
}

int MapPrep::apply(Params& given) const {
  if (given.has("traffic-cost")) return 0;
  given.set("traffic-cost", number(traffic_cost));
  return 1;
}

void save_prep(const MapPrep& prep, const std::string& path) {
  std::ofstream out(path);
  if (!out || !(out << prep.to_json().dump(2) << "\n")) throw PrepError("cannot write the preparation file " + path);
}

MapPrep load_prep(const std::string& path, const Grid& grid, int agents, ActionModel model) {
  std::ifstream in(path);
  if (!in) throw PrepError("cannot read the preparation file " + path);
  MapPrep p;
  try {
    const nlohmann::json j = nlohmann::json::parse(in);
    if (j.value("format", "") != MapPrep::kFormat)
      throw PrepError("not a preparation file (format is not " + std::string(MapPrep::kFormat) + ")");
    p.map_key = j.at("map_key").get<std::string>();
    p.width = j.at("width"), p.height = j.at("height"), p.agents = j.at("agents");
    p.model = parse_action_model(j.at("action_model").get<std::string>());
    p.planner = j.at("planner").get<std::string>();
    p.steps = j.at("steps"), p.step_budget_s = j.at("step_budget_s"), p.seed = j.at("seed"), p.seeds = j.at("seeds");
    for (auto& t : j.at("trials"))
      p.trials.push_back({t.at("traffic_cost"), t.at("seed"), t.at("goals"), t.at("seconds"), p.steps});
    p.traffic_cost = j.at("traffic_cost");
  } catch (const std::exception& e) {
    throw PrepError("preparation file " + path + ": " + e.what());
  }
  if (!(p.traffic_cost >= 0 && p.traffic_cost <= 8))
    throw PrepError("preparation file " + path + ": traffic_cost " + number(p.traffic_cost) + " is not in [0, 8]");
  const std::string key = map_key(grid);
  if (p.map_key != key)
    throw PrepError("preparation file " + path + " was made for another map (key " + p.map_key + ", this map " +
                    key + ")");
  if (p.agents != agents)
    throw PrepError("preparation file " + path + " was made for " + std::to_string(p.agents) + " agents, not " +
                    std::to_string(agents));
  if (p.model != model)
    throw PrepError("preparation file " + path + " was made for the " + action_model_name(p.model) +
                    " action model, not " + action_model_name(model));
  return p;
}

std::string prep_file_name(const Grid& grid, int agents, ActionModel model) {
  return "gdrhcr-prep-" + map_key(grid) + "-" + std::to_string(agents) + "-" + action_model_name(model) + ".json";
}

}  // namespace gdrhcr
