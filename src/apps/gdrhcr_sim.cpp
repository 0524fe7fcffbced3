// gdrhcr_sim: run one lifelong MAPF simulation from the command line and write its figures.
//
//   gdrhcr_sim --map maps/warehouse-10-20-10-2-1.map --tasks mapd --planner pibt \
//              --agents 400 --steps 500 --seed 1 --out result.json [--paths paths.txt]
//
// Planner parameters (--H, --alpha, --V, ...) are read against the planner's parameter table
// (planner_params.hpp); `--list-params` prints it with the values in force for the map and fleet.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include "gdrhcr/distinct_goal_stream.hpp"
#include "gdrhcr/lorr_io.hpp"
#include "gdrhcr/map_prep.hpp"
#include "gdrhcr/mapf_in_rotation.hpp"
#include "gdrhcr/planner_params.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {

const char* kUsage =
    "usage: gdrhcr_sim --map FILE [options]\n"
    "  --map FILE          MovingAI .map or RHCR kiva .map (required unless --lorr-problem)\n"
    "  --lorr-problem FILE a LoRR Start-Kit problem JSON: its map, agents (teamSize starts) and\n"
    "                      task list (taskAssignmentStrategy; numTasksReveal is the default\n"
    "                      --lookahead); replaces --map, --agents, --tasks; runs in the\n"
    "                      rotation model unless --action-model mapf\n"
    "  --turns HOW         in rotation: native (the planner plans with headings; default) or\n"
    "                      mapf-wait (its mapf steps executed with turns and waits)\n"
    "  --lorr-out FILE     also write the run as the Start-Kit's output JSON, in the run's action\n"
    "                      model (rotation: MAPF_T, F/R/C/W; mapf: PlanViz's MAPF letters)\n"
    "  --tasks random|mapd task stream (default random)\n"
    "  --pickups FILE      MAPD pickup cells, 'x y' per line (default: MAP.pickups beside\n"
    "                      the map if present, else the rule in the README)\n"
    "  --deliveries FILE   MAPD delivery cells, 'x y' per line (default: the map's rule)\n"
    "  --planner NAME      planner: %s (default pibt)\n"
    "  --action-model M    mapf (wait or move to a 4-neighbour; default) or rotation (LoRR's\n"
    "                      MAPF_T: heading E/S/W/N, forward, rotate either way or wait; all\n"
    "                      agents start facing east); the result records action_model\n"
    "  --agents N          number of agents (default 100)\n"
    "  --steps N           timesteps to simulate (default 500)\n"
    "  --seed N            seed for starts, tasks and planner tie-breaks (default 0)\n"
    "  --lookahead N       goals known ahead per agent, current one included (default 3)\n"
    "  --distinct-goals 0|1 1: never hand out a goal another agent holds (redrawn; with\n"
    "                      --lookahead 1, LLLG's rule: not another agent's current goal)\n"
    "  --dist-budget-mb N  memory budget of the distance-table cache (default 256)\n"
    "  --all-rows 0|1      1: before the first step, every free cell's distance row when they all\n"
    "                      fit in --dist-budget-mb (as the Start-Kit adapter does in its\n"
    "                      preprocessing phase; the result's all_rows records the time), so no\n"
    "                      step computes a row (default 0)\n"
    "  --out FILE          write the result JSON here (default: standard output)\n"
    "  --paths FILE        write executed paths, one line per agent: 'i: (x,y),(x,y),...'\n"
    "  --quiet             no summary on standard error\n"
    "  --list-params       print the planner's parameters with the values in force for --map and\n"
    "                      --agents (or --lorr-problem), then exit\n"
    "  --prepare FILE      offline preparation (rotation model): simulate --steps steps (1,500,\n"
    "                      long enough for a long run's jams to form) per candidate traffic cost\n"
    "                      and seed (--seed, --seed + 1) with --agents on --map, random goals;\n"
    "                      write the choice to FILE (map_prep.hpp), then exit\n"
    "  --prep FILE         use a preparation file made for this map, fleet size and model: its\n"
    "                      traffic cost applies unless --traffic-cost is given\n"
    "  --PARAM VALUE       a planner parameter; each planner's are listed below\n";

// Every planner's parameters: name, range, default (or the rule that picks it), meaning.
std::string parameter_help() {
  std::string out;
  for (auto& name : planner_names()) {
    out += "\n--planner " + name + " parameters (range, default or the rule picking it from the map and fleet):\n";
    for (auto& s : planner_param_specs(name)) {
      std::string def = s.rule.empty() ? s.value : "rule " + s.rule;
      if (!s.paper.empty()) def += " (paper " + s.paper + ")";
      out += "  --" + s.name + " " + s.range_text() + ", default " + def + ": " + s.meaning + "\n";
    }
  }
  out += "\nrules:\n";
  for (auto& r : param_rules()) out += "  " + r.name + ": " + r.why + "\n";
  return out;
}

std::string planner_list() {
  std::string s;
  for (auto& n : planner_names()) s += (s.empty() ? "" : ", ") + n;
  return s;
}

void write_paths(const Grid& grid, const SimResult& r, const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write paths file " + path);
  for (size_t i = 0; i < r.paths.size(); ++i) {
    out << i << ":";
    for (Cell c : r.paths[i]) out << "(" << grid.x_of(c) << "," << grid.y_of(c) << "),";
    out << "\n";
  }
}

// The command line as parameters; flags (no value) apart. Returns an exit code, or -1 to go on.
struct Flags {
  bool quiet = false, help = false, list_params = false;
};
int parse_args(int argc, char** argv, Params& args, Flags& flags) {
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "-h" || a == "--help") { flags.help = true; continue; }
    if (a == "--quiet") { flags.quiet = true; continue; }
    if (a == "--list-params") { flags.list_params = true; continue; }
    if (a.rfind("--", 0) != 0 || a.size() < 3) {
      std::fprintf(stderr, "gdrhcr_sim: unexpected argument '%s' (options start with --)\n", a.c_str());
      return 2;
    }
    std::string key = a.substr(2), value;
    if (auto eq = key.find('='); eq != std::string::npos) {
      value = key.substr(eq + 1);
      key = key.substr(0, eq);
    } else if (i + 1 < argc) {
      value = argv[++i];
    } else {
      std::fprintf(stderr, "gdrhcr_sim: option --%s needs a value\n", key.c_str());
      return 2;
    }
    if (args.has(key)) {
      std::fprintf(stderr, "gdrhcr_sim: option --%s given twice\n", key.c_str());
      return 2;
    }
    args.set(key, value);
  }
  return -1;
}

// The run's options (everything but the planner's own parameters).
struct RunOptions {
  std::string lorr_path, lorr_out, map_path, task_kind, pickups_file, deliveries_file, planner;
  std::string out_path, paths_path, prepare_path, prep_path;
  int agents = 100, steps = 500, lookahead = 3, budget_mb = 256;
  uint64_t seed = 0;
  bool distinct_goals = false;
  bool all_rows = false;
  ActionModel action_model = ActionModel::kMapf;
  TurnPlanning turns = TurnPlanning::kNative;
  std::unique_ptr<LorrProblem> lorr;
};

ActionModel read_action_model(Params& args, const char* fallback) {
  try {
    return parse_action_model(args.get_string("action-model", fallback));
  } catch (const std::invalid_argument& e) {
    throw ParamError(std::string("--action-model: ") + e.what());
  }
}

RunOptions read_options(Params& args) {
  RunOptions o;
  o.lorr_path = args.get_string("lorr-problem", "");
  o.lorr_out = args.get_string("lorr-out", "");
  if (!o.lorr_path.empty()) {
    for (const char* k : {"map", "agents", "tasks", "pickups", "deliveries"})
      if (args.has(k)) throw ParamError(std::string("--") + k + " cannot be combined with --lorr-problem (the problem file sets it)");
    o.lorr = std::make_unique<LorrProblem>(load_lorr_problem(o.lorr_path));
  }
  o.map_path = o.lorr ? o.lorr->map_path : args.get_string("map", "");
  if (o.map_path.empty()) throw ParamError("--map is required\n" + std::string("run with --help for the options"));
  o.task_kind = o.lorr ? "lorr" : args.get_choice("tasks", "random", {"random", "mapd"});
  o.pickups_file = args.get_string("pickups", "");
  o.deliveries_file = args.get_string("deliveries", "");
  o.planner = args.get_string("planner", "pibt");
  o.action_model = read_action_model(args, o.lorr ? "rotation" : "mapf");  // LoRR's own model: MAPF_T
  try {
    o.turns = parse_turn_planning(args.get_string("turns", turn_planning_name(o.lorr ? kLorrTurnPlanning : o.turns)));
  } catch (const std::invalid_argument& e) {
    throw ParamError(std::string("--turns: ") + e.what());
  }
  o.agents = o.lorr ? o.lorr->team_size : args.get_int("agents", 100, 1, 10000000);
  o.steps = args.get_int("steps", 500, 1, 100000000);
  o.seed = args.get_u64("seed", 0);
  o.lookahead = args.get_int("lookahead", o.lorr ? o.lorr->num_tasks_reveal : 3, 1, 1000);
  o.budget_mb = args.get_int("dist-budget-mb", 256, 1, 1 << 20);
  o.all_rows = args.get_int("all-rows", 0, 0, 1) == 1;
  o.distinct_goals = args.get_int("distinct-goals", 0, 0, 1) == 1;
  o.out_path = args.get_string("out", "");
  o.paths_path = args.get_string("paths", "");
  o.prepare_path = args.get_string("prepare", "");
  o.prep_path = args.get_string("prep", "");
  if (o.task_kind == "random" && (!o.pickups_file.empty() || !o.deliveries_file.empty()))
    throw ParamError("--pickups/--deliveries only apply to --tasks mapd");
  return o;
}

// The task stream the options ask for; `info` describes it for the result record.
std::unique_ptr<TaskStream> make_tasks(const RunOptions& o, const Grid& grid, nlohmann::json& info,
                                       TaskListStream*& task_list) {
  std::unique_ptr<TaskStream> tasks;
  info = {{"kind", o.task_kind}};
  if (o.lorr) {
    auto list = std::make_unique<TaskListStream>(grid, o.lorr->tasks, o.lorr->team_size, o.lorr->strategy);
    task_list = list.get();
    tasks = std::move(list);
    info = {{"kind", "lorr"}, {"problem", o.lorr_path}, {"tasks", o.lorr->tasks.size()},
            {"strategy", TaskListStream::to_string(o.lorr->strategy)}, {"num_tasks_reveal", o.lorr->num_tasks_reveal}};
  } else if (o.task_kind == "random") {
    tasks = std::make_unique<RandomNavigationStream>(grid, o.seed);
  } else {
    MapdCells cells = mapd_cells_for_map(grid, o.map_path);
    if (!o.pickups_file.empty()) cells.pickups = load_cell_list(grid, o.pickups_file), cells.rule = "given lists";
    if (!o.deliveries_file.empty()) cells.deliveries = load_cell_list(grid, o.deliveries_file), cells.rule = "given lists";
    info["rule"] = cells.rule;
    info["pickups"] = cells.pickups.size();
    info["deliveries"] = cells.deliveries.size();
    tasks = std::make_unique<PickupDeliveryStream>(grid, cells.pickups, cells.deliveries, o.seed);
  }
  if (o.distinct_goals) {
    if (o.lorr) throw ParamError("--distinct-goals cannot be combined with --lorr-problem (its task list is fixed)");
    tasks = std::make_unique<DistinctGoalStream>(std::move(tasks));
    info["distinct_goals"] = true;
  }
  return tasks;
}

// The result record: the run's figures, every parameter in force and where its value came from.
nlohmann::json result_json(const RunOptions& o, const SimResult& r, const Planner& planner,
                           const PlannerParams& values, const nlohmann::json& task_info, const DistTable& dist) {
  nlohmann::json j = r.to_json();
  j["map"] = o.map_path;
  j["planner"] = planner.name();
  j["seed"] = o.seed;
  j["tasks"] = task_info;
  nlohmann::json params = values.to_json();
  params["steps"] = o.steps;
  params["agents"] = o.agents;
  params["seed"] = o.seed;
  params["tasks"] = o.task_kind;
  params["lookahead"] = o.lookahead;
  params["action_model"] = action_model_name(o.action_model);
  if (o.action_model == ActionModel::kRotation) params["turns"] = turn_planning_name(o.turns);
  params["dist_budget_mb"] = o.budget_mb;
  params["all_rows"] = o.all_rows;
  j["params"] = params;
  for (auto& v : values.values()) j["param_sources"][v.spec->name] = v.source;
  j["stats"] = planner.stats();
  j["dist_table"] = {{"rows_cached", dist.cached_rows()},       {"bytes_cached", dist.cached_bytes()},
                     {"bytes_peak", dist.peak_bytes()},         {"bytes_per_row", dist.row_bytes()},
                     {"index_bytes", dist.index_bytes()},       {"budget_bytes", dist.budget_bytes()},
                     {"bfs_runs", dist.bfs_count()},            {"evictions", dist.evictions()},
                     {"over_budget_inserts", dist.over_budget_inserts()}};
  return j;
}

void write_text(const std::string& path, const std::string& text) {
  if (path.empty()) {
    std::cout << text;
    return;
  }
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << text;
}

// --prepare: the offline preparation's trials, written to the file.
int prepare(const RunOptions& o, const Grid& grid, const Params& args, const Flags& flags) {
  PrepOptions po;
  po.agents = o.agents;
  po.model = o.action_model;
  po.planner = o.planner;
  po.given = args;
  po.steps = o.steps;
  po.seed = o.seed;
  po.dist_budget_mb = o.budget_mb;
  const MapPrep prep = prepare_map(grid, po);
  save_prep(prep, o.prepare_path);
  if (!flags.quiet)
    for (auto& t : prep.trials)
      std::fprintf(stderr, "traffic-cost %g, seed %llu: %ld goals in %d steps (%.1f s)\n", t.traffic_cost,
                   static_cast<unsigned long long>(t.seed), t.goals, prep.steps, t.seconds);
  std::printf("%s: traffic-cost %g\n", o.prepare_path.c_str(), prep.traffic_cost);
  return 0;
}

int run(Params& args, const Flags& flags) {
  const RunOptions o = read_options(args);
  const Grid grid = o.lorr ? std::move(o.lorr->grid) : Grid::load(o.map_path);
  if (!o.prepare_path.empty()) return prepare(o, grid, args, flags);
  nlohmann::json prep_record;
  if (!o.prep_path.empty()) {
    const MapPrep prep = load_prep(o.prep_path, grid, o.agents, o.action_model);
    prep_record = {{"file", o.prep_path}, {"applied", prep.apply(args) > 0}, {"prep", prep.to_json()}};
  }
  const PlannerParams values = PlannerParams::resolve(o.planner, args, MapFacts(grid, o.agents, o.action_model));
  args.check_all_used("gdrhcr_sim --planner " + o.planner);
  if (flags.list_params) {
    std::printf("%s parameters for %s, %d agents (preset %s):\n%s", o.planner.c_str(), o.map_path.c_str(), o.agents,
                values.preset().c_str(), values.format().c_str());
    return 0;
  }
  DistTable dist(grid, o.action_model, size_t(o.budget_mb) << 20, step_costs(values, o.action_model));
  nlohmann::json all_rows_record;
  if (o.all_rows) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto all = dist.prefetch_all();
    all_rows_record = {{"fit", all.fit}, {"bytes", all.bytes}, {"rows", all.computed},
                       {"seconds", std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()}};
    if (!all.fit)
      std::fprintf(stderr, "gdrhcr_sim: --all-rows: every free cell's row needs %zu MB, more than --dist-budget-mb %d\n",
                   (all.bytes >> 20) + 1, o.budget_mb);
  }
  nlohmann::json task_info;
  TaskListStream* task_list = nullptr;
  std::unique_ptr<TaskStream> tasks = make_tasks(o, grid, task_info, task_list);
  const std::vector<Cell> starts = o.lorr ? o.lorr->starts : random_starts(grid, o.agents, o.seed);
  auto planner = make_planner_in(values, grid, o.agents, o.seed, o.action_model, o.turns);

  SimOptions opt;
  opt.steps = o.steps;
  opt.lookahead = o.lookahead;
  opt.record_paths = !o.paths_path.empty() || !o.lorr_out.empty();
  opt.action_model = o.action_model;
  RecordingTaskStream recorded(*tasks);
  const SimResult r = run_simulation(grid, dist, recorded, *planner, starts, opt);

  if (!o.paths_path.empty()) write_paths(grid, r, o.paths_path);
  if (!o.lorr_out.empty()) {
    std::vector<std::vector<long>> ids;
    if (task_list)
      for (int i = 0; i < o.agents; ++i) ids.push_back(task_list->assigned_ids(i));
    const bool rotation = o.action_model == ActionModel::kRotation;
    write_text(o.lorr_out,
               lorr_output(grid, r.paths, recorded.goals(), o.lookahead, ids, rotation ? &r.headings : nullptr).dump() + "\n");
  }
  nlohmann::json result = result_json(o, r, *planner, values, task_info, dist);
  if (!all_rows_record.is_null()) result["all_rows"] = all_rows_record;
  if (!prep_record.is_null()) {
    result["prep"] = prep_record;
    if (prep_record["applied"].get<bool>()) result["param_sources"]["traffic-cost"] = "prep " + o.prep_path;
  }
  write_text(o.out_path, result.dump(2) + "\n");
  if (!flags.quiet)
    std::fprintf(stderr,
                 "%s (%s model) on %s, %d agents, %d steps: throughput %.3f (free flow %.3f), %ld goals, "
                 "0 collisions, plan time mean %.6f s max %.6f s, wall %.2f s\n",
                 planner->name().c_str(), action_model_name(o.action_model), o.map_path.c_str(), o.agents, o.steps, r.throughput, r.free_flow_throughput,
                 r.goals_reached, r.plan_time_mean_s, r.plan_time_max_s, r.wall_time_s);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Params args;
  Flags flags;
  if (const int code = parse_args(argc, argv, args, flags); code >= 0) return code;
  if (flags.help) {
    std::printf(kUsage, planner_list().c_str());
    std::printf("%s", parameter_help().c_str());
    return 0;
  }
  try {
    return run(args, flags);
  } catch (const CollisionError& e) {
    std::fprintf(stderr, "gdrhcr_sim: COLLISION (planner bug): %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gdrhcr_sim: error: %s\n", e.what());
    return 2;
  }
}
