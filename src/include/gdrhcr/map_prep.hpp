// Offline preparation per map (issue 24, item 2): settings that pay off on one map and fleet
// but not on another, chosen once by simulation on that map and cached to a file keyed by it.
//
// Today it chooses the traffic cost (dist_table.hpp). Spreading traffic over a city's many
// near-equal routes lifts Paris_1_256 by a quarter, while on a warehouse, whose main corridors
// every route needs, the same cost loses a third; no single structural measure told them apart.
// So, as the guidance-graph optimisation of Zhang et al. (IJCAI 2024) does with a simulator in
// the loop, preparation runs the planner on the map itself, with the fleet's size and random
// goals, once per candidate cost and seed, and keeps the one that reaches the most goals over the
// seeds. The first candidate (none) is kept unless another beats it by kMargin, so noise does not
// switch it. Trials run the planner as the run will: with the run's step budget when it has one,
// since the anytime search (window_lns.hpp) runs only with a budget and changes which cost wins
// (Paris: 2 without the search, 1 with it). A crowded fleet (rule crowded-fleet,
// planner_params.hpp) tries every candidate too: once PIBT's configurations are carried out to
// the end, its trials are no longer noise.
// The League's Start-Kit gives a preprocessing phase for such work (the LoRR adapter runs it
// there, lorr_bridge.hpp); the ROS node and gdrhcr_sim load a file made by
// `gdrhcr_sim --prepare`.
//
// Optional by design: a plan never needs it. Loading checks the file's format and that it was
// made for this map (a key over the map's size and cells) and fleet size, and throws PrepError
// naming the file and the problem; callers then go on without it.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/params.hpp"

namespace gdrhcr {

struct PrepError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A key for the map: FNV-1a over its width, height and free cells, as 16 hex digits.
std::string map_key(const Grid& grid);

struct PrepOptions {
  int agents = 0;
  ActionModel model = ActionModel::kRotation;
  std::string planner = "gd-rhcr";
  Params given;                               // the planner's parameters besides the tuned ones
  std::vector<double> traffic_costs{0, 1, 2};  // candidates; the first is the fallback
  int steps = 1500;                           // per trial: long enough for a long run's jams
  int seeds = 2;                              // trials per candidate: seeds seed, seed + 1, ...
  double step_budget_s = 0;                   // the planner's step budget in trials, the run's
                                              //   (0 = none: trials then repeat exactly)
  double time_limit_s = 0;                    // > 0: the first trial stops at its share of it,
                                              //   and the others run as many steps
  uint64_t seed = 1;
  int dist_budget_mb = 1024;                  // the trials' distance-table cache
};

struct PrepTrial {
  double traffic_cost = 0;
  uint64_t seed = 0;
  long goals = 0;
  double seconds = 0;
  int steps = 0;
};

struct MapPrep {
  static constexpr const char* kFormat = "gdrhcr-prep/2";  // 2: candidates 0, 1, 2, trials at the run's budget
  static constexpr double kMargin = 0.05;  // a candidate replaces the first one if 5% better
  std::string map_key;
  int width = 0, height = 0, agents = 0;
  ActionModel model = ActionModel::kRotation;
  std::string planner;
  int steps = 0;
  double step_budget_s = 0;
  uint64_t seed = 0;
  int seeds = 0;
  std::vector<PrepTrial> trials;
  double traffic_cost = 0;  // the choice
  long goals_of(double traffic_cost) const;  // over the seeds

  nlohmann::json to_json() const;
  // Sets the prepared parameters in `given` unless they are given already; returns how many.
  int apply(Params& given) const;
};

// Runs the trials (in the rotation model only: the traffic cost has no effect elsewhere).
// Throws ParamError for a bad option or parameter.
MapPrep prepare_map(const Grid& grid, const PrepOptions& options);

void save_prep(const MapPrep& prep, const std::string& path);
// Throws PrepError naming `path` when it cannot be read, is not a preparation file, or was made
// for another map, fleet size or action model.
MapPrep load_prep(const std::string& path, const Grid& grid, int agents, ActionModel model);

// The cache file's name in a directory: the map key, the fleet size and the action model.
std::string prep_file_name(const Grid& grid, int agents, ActionModel model);

}  // namespace gdrhcr
