// The one table of planner parameters. Every parameter of every planner is declared once in
// src/lib/planner_params.cpp: name, type, range, one-line meaning, the product default and the
// paper preset's value, and, where the default depends on the map or the fleet, the named rule
// that picks it. The command line (`gdrhcr_sim --list-params`), the ROS node, config/*.yaml,
// dynamic_reconfigure and the README's parameter list all come from it or are checked against
// it by a test; the result JSON records the values it resolved.
#pragma once

#include "gdrhcr/action_model.hpp"

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/params.hpp"

namespace gdrhcr {

enum class ParamType { kInt, kReal, kFlag, kChoice };

struct ParamSpec {
  std::string name;  // canonical (Params::canonical): "c-soft", "k-threshold", "V"
  ParamType type = ParamType::kInt;
  double min = 0, max = 0;           // kInt, kReal (inclusive); kFlag is 0 or 1
  std::vector<std::string> choices;  // kChoice
  std::string meaning;               // one line
  std::string value;                 // the product default, when no rule picks it
  std::string rule;                  // the named rule that picks the default (ParamRule), or ""
  std::string paper;                 // the value under `--preset paper`; "" = as the default
  std::string range_text() const;
};

// What the map-dependent rules read: the map and the fleet.
class MapFacts {
 public:
  MapFacts(const Grid& grid, int num_agents, ActionModel model = ActionModel::kMapf)
      : grid_(&grid), num_agents_(num_agents), model_(model) {}
  int num_agents() const { return num_agents_; }
  ActionModel model() const { return model_; }
  double cut_cell_share() const;  // computed once, on first use
  double fleet_share() const;     // agents per free cell
  size_t free_cells() const;
  bool open_areas() const;        // the map has open areas beside aisles (lanes.hpp); computed once
 private:
  const Grid* grid_;
  int num_agents_;
  ActionModel model_;
  mutable std::optional<double> cut_share_;
  mutable std::optional<bool> open_areas_;
};

class PlannerParams;

// Rule crowded-fleet's test: the fleet holds more than 90% of the free cells.
bool crowded_fleet(const MapFacts& facts);

// A named rule picking the default of one or more parameters from the map, the fleet and the
// values resolved before them (table order).
struct ParamRule {
  std::string name;
  std::string why;     // one line
  std::string figure;  // where docs/results.md shows the figure behind it
  std::string (*pick)(const std::string& param, const MapFacts& facts, const PlannerParams& earlier);
};
const std::vector<ParamRule>& param_rules();

struct ParamValue {
  const ParamSpec* spec = nullptr;
  std::string text;    // the value in force
  std::string source;  // "given", "default", "paper" or "rule NAME"
};

// The values in force for one planner on one map and fleet: given ones (checked against the
// table, errors name the parameter), else the preset's default or its rule.
class PlannerParams {
 public:
  // Reads (and marks used) the planner's parameters in `given`, "preset" included. Throws
  // ParamError for an unknown planner or a bad value; parameters the planner does not have are
  // left unread in `given` (Params::check_all_used names them).
  static PlannerParams resolve(const std::string& planner, Params& given, const MapFacts& facts);

  const std::string& planner() const { return planner_; }
  const std::string& preset() const { return preset_; }
  const std::vector<ParamValue>& values() const { return values_; }
  bool has(const std::string& name) const { return find(name) != nullptr; }
  int integer(const std::string& name) const;
  double real(const std::string& name) const;
  bool flag(const std::string& name) const;
  const std::string& text(const std::string& name) const;

  // {name with '_' for '-': typed value} for every parameter, "preset" included.
  nlohmann::json to_json() const;
  // The table as `gdrhcr_sim --list-params` prints it: name, value, default or rule, range, meaning.
  std::string format() const;

 private:
  const ParamValue* find(const std::string& name) const;
  const ParamValue& at(const std::string& name) const;
  std::string planner_, preset_;
  std::vector<ParamValue> values_;
};

// The distance table's step costs the parameters ask for (0 when the planner has none). Throws
// ParamError when one is asked for outside the rotation model.
StepCosts step_costs(const PlannerParams& values, ActionModel model);

// Every parameter of `planner`, in table order. Throws ParamError for an unknown planner.
const std::vector<ParamSpec>& planner_param_specs(const std::string& planner);
// True when `planner` has a parameter of that name (any spelling Params::canonical accepts).
bool planner_has_param(const std::string& planner, const std::string& name);

}  // namespace gdrhcr
