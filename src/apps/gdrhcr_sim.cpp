// gdrhcr_sim: run one lifelong MAPF simulation from the command line and write its figures.
//
//   gdrhcr_sim --map maps/warehouse-10-20-10-2-1.map --tasks mapd --planner pibt \
//              --agents 400 --steps 500 --seed 1 --out result.json [--paths paths.txt]
//
// Planner parameters (--H, --alpha, --V, ...) are passed through to the planner, which rejects
// the ones it does not know.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include "gdrhcr/distinct_goal_stream.hpp"
#include "gdrhcr/lorr_io.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {

const char* kUsage =
    "usage: gdrhcr_sim --map FILE [options]\n"
    "  --map FILE          MovingAI .map or RHCR kiva .map (required unless --lorr-problem)\n"
    "  --lorr-problem FILE a LoRR Start-Kit problem JSON: its map, agents (teamSize starts) and\n"
    "                      task list (taskAssignmentStrategy; numTasksReveal is the default\n"
    "                      --lookahead); replaces --map, --agents, --tasks\n"
    "  --lorr-out FILE     also write the run as LoRR output JSON (PlanViz, MAPF model)\n"
    "  --tasks random|mapd task stream (default random)\n"
    "  --pickups FILE      MAPD pickup cells, 'x y' per line (default: MAP.pickups beside\n"
    "                      the map if present, else the rule in the README)\n"
    "  --deliveries FILE   MAPD delivery cells, 'x y' per line (default: the map's rule)\n"
    "  --planner NAME      planner: %s (default pibt)\n"
    "  --agents N          number of agents (default 100)\n"
    "  --steps N           timesteps to simulate (default 500)\n"
    "  --seed N            seed for starts, tasks and planner tie-breaks (default 0)\n"
    "  --lookahead N       goals known ahead per agent, current one included (default 3)\n"
    "  --distinct-goals 0|1 1: never hand out a goal another agent holds (redrawn; with\n"
    "                      --lookahead 1, LLLG's rule: not another agent's current goal)\n"
    "  --dist-budget-mb N  memory budget of the distance-table cache (default 256)\n"
    "  --out FILE          write the result JSON here (default: standard output)\n"
    "  --paths FILE        write executed paths, one line per agent: 'i: (x,y),(x,y),...'\n"
    "  --quiet             no summary on standard error\n"
    "  planner options     e.g. --H 20 --alpha 5 --timeout 60 --V 2 --c-soft 1 --threads 2\n";

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

}  // namespace

int main(int argc, char** argv) {
  Params args;
  bool quiet = false;
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::printf(kUsage, planner_list().c_str());
      return 0;
    }
    if (a == "--quiet") { quiet = true; continue; }
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
  try {
    const std::string lorr_path = args.get_string("lorr-problem", "");
    const std::string lorr_out = args.get_string("lorr-out", "");
    std::unique_ptr<LorrProblem> lorr;
    if (!lorr_path.empty()) {
      for (const char* k : {"map", "agents", "tasks", "pickups", "deliveries"})
        if (args.has(k)) throw ParamError(std::string("--") + k + " cannot be combined with --lorr-problem (the problem file sets it)");
      lorr = std::make_unique<LorrProblem>(load_lorr_problem(lorr_path));
    }
    const std::string map_path = lorr ? lorr->map_path : args.get_string("map", "");
    if (map_path.empty()) throw ParamError("--map is required\n" + std::string("run with --help for the options"));
    const std::string task_kind = lorr ? "lorr" : args.get_choice("tasks", "random", {"random", "mapd"});
    const std::string pickups_file = args.get_string("pickups", "");
    const std::string deliveries_file = args.get_string("deliveries", "");
    const std::string planner_name = args.get_string("planner", "pibt");
    const int agents = lorr ? lorr->team_size : args.get_int("agents", 100, 1, 10000000);
    const int steps = args.get_int("steps", 500, 1, 100000000);
    const uint64_t seed = args.get_u64("seed", 0);
    const int lookahead = args.get_int("lookahead", lorr ? lorr->num_tasks_reveal : 3, 1, 1000);
    const int budget_mb = args.get_int("dist-budget-mb", 256, 1, 1 << 20);
    const bool distinct_goals = args.get_int("distinct-goals", 0, 0, 1) == 1;
    const std::string out_path = args.get_string("out", "");
    const std::string paths_path = args.get_string("paths", "");
    if (task_kind == "random" && (!pickups_file.empty() || !deliveries_file.empty()))
      throw ParamError("--pickups/--deliveries only apply to --tasks mapd");

    const Grid grid = lorr ? std::move(lorr->grid) : Grid::load(map_path);
    DistTable dist(grid, size_t(budget_mb) << 20);
    std::unique_ptr<TaskStream> tasks;
    nlohmann::json task_info = {{"kind", task_kind}};
    TaskListStream* task_list = nullptr;
    if (lorr) {
      auto list = std::make_unique<TaskListStream>(grid, lorr->tasks, lorr->team_size, lorr->strategy);
      task_list = list.get();
      tasks = std::move(list);
      task_info = {{"kind", "lorr"}, {"problem", lorr_path}, {"tasks", lorr->tasks.size()},
                   {"strategy", TaskListStream::to_string(lorr->strategy)}, {"num_tasks_reveal", lorr->num_tasks_reveal}};
    } else if (task_kind == "random") {
      tasks = std::make_unique<RandomNavigationStream>(grid, seed);
    } else {
      MapdCells cells = mapd_cells_for_map(grid, map_path);
      if (!pickups_file.empty()) cells.pickups = load_cell_list(grid, pickups_file), cells.rule = "given lists";
      if (!deliveries_file.empty()) cells.deliveries = load_cell_list(grid, deliveries_file), cells.rule = "given lists";
      task_info["rule"] = cells.rule;
      task_info["pickups"] = cells.pickups.size();
      task_info["deliveries"] = cells.deliveries.size();
      tasks = std::make_unique<PickupDeliveryStream>(grid, cells.pickups, cells.deliveries, seed);
    }
    if (distinct_goals) {
      if (lorr) throw ParamError("--distinct-goals cannot be combined with --lorr-problem (its task list is fixed)");
      tasks = std::make_unique<DistinctGoalStream>(std::move(tasks));
      task_info["distinct_goals"] = true;
    }
    const std::vector<Cell> starts = lorr ? lorr->starts : random_starts(grid, agents, seed);
    auto planner = make_planner(planner_name, args, grid, agents, seed);
    args.check_all_used("gdrhcr_sim --planner " + planner_name);

    SimOptions opt;
    opt.steps = steps;
    opt.lookahead = lookahead;
    opt.record_paths = !paths_path.empty() || !lorr_out.empty();
    RecordingTaskStream recorded(*tasks);
    const SimResult r = run_simulation(grid, dist, recorded, *planner, starts, opt);

    nlohmann::json j = r.to_json();
    j["map"] = map_path;
    j["planner"] = planner->name();
    j["seed"] = seed;
    j["tasks"] = task_info;
    nlohmann::json params = planner->params();
    params["steps"] = steps;
    params["agents"] = agents;
    params["seed"] = seed;
    params["tasks"] = task_kind;
    params["lookahead"] = lookahead;
    params["dist_budget_mb"] = budget_mb;
    j["params"] = params;
    j["stats"] = planner->stats();
    j["dist_table"] = {{"rows_cached", dist.cached_rows()},
                       {"bytes_cached", dist.cached_bytes()},
                       {"bytes_peak", dist.peak_bytes()},
                       {"bytes_per_row", dist.row_bytes()},
                       {"index_bytes", dist.index_bytes()},
                       {"budget_bytes", dist.budget_bytes()},
                       {"bfs_runs", dist.bfs_count()},
                       {"evictions", dist.evictions()},
                       {"over_budget_inserts", dist.over_budget_inserts()}};
    if (!paths_path.empty()) write_paths(grid, r, paths_path);
    if (!lorr_out.empty()) {
      std::vector<std::vector<long>> ids;
      if (task_list)
        for (int i = 0; i < agents; ++i) ids.push_back(task_list->assigned_ids(i));
      std::ofstream lo(lorr_out);
      if (!lo) throw std::runtime_error("cannot write " + lorr_out);
      lo << lorr_output(grid, r.paths, recorded.goals(), lookahead, ids).dump() << "\n";
    }
    const std::string text = j.dump(2) + "\n";
    if (out_path.empty()) {
      std::cout << text;
    } else {
      std::ofstream out(out_path);
      if (!out) throw std::runtime_error("cannot write " + out_path);
      out << text;
    }
    if (!quiet)
      std::fprintf(stderr,
                   "%s on %s, %d agents, %d steps: throughput %.3f (free flow %.3f), %ld goals, "
                   "0 collisions, plan time mean %.6f s max %.6f s, wall %.2f s\n",
                   planner->name().c_str(), map_path.c_str(), agents, steps, r.throughput,
                   r.free_flow_throughput, r.goals_reached, r.plan_time_mean_s, r.plan_time_max_s,
                   r.wall_time_s);
    return 0;
  } catch (const CollisionError& e) {
    std::fprintf(stderr, "gdrhcr_sim: COLLISION (planner bug): %s\n", e.what());
    return 3;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gdrhcr_sim: error: %s\n", e.what());
    return 2;
  }
}
