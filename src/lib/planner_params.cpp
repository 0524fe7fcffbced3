// The one table of planner parameters (planner_params.hpp): the product default and the paper
// preset are both defined here, and nowhere else. Defaults that depend on the map or the fleet
// come from the named rules below; the figures behind each are in docs/results.md, section
// "The product default's rules".
#include "gdrhcr/planner_params.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>

#include "gdrhcr/cut_cells.hpp"
#include "gdrhcr/lanes.hpp"
#include "gdrhcr/pibt.hpp"

namespace gdrhcr {

double MapFacts::cut_cell_share() const {
  if (!cut_share_) cut_share_ = gdrhcr::cut_cell_share(*grid_);
  return *cut_share_;
}

// Fleets filling more than 90% of the free cells (rule crowded-fleet).
constexpr double kCrowdedFleet = 0.9;
bool crowded_fleet(const MapFacts& f) { return f.fleet_share() > kCrowdedFleet; }

double MapFacts::fleet_share() const { return double(num_agents_) / std::max<size_t>(1, free_cells()); }

size_t MapFacts::free_cells() const { return grid_->free_cells().size(); }

bool MapFacts::open_areas() const {
  if (!open_areas_) open_areas_ = derive_open_areas(*grid_).num_lines() > 0;
  return *open_areas_;
}

namespace {

// ---------------------------------------------------------------------------------------------
// Named rules.
constexpr int kThousands = 2000;  // fleets past this many agents plan guidance lazily
bool thousands(const MapFacts& f) { return f.num_agents() > kThousands; }
// Maps where at least 1% of the free cells are cut cells (dead ends, one-lane passages).
bool many_cut_cells(const MapFacts& f) { return f.cut_cell_share() >= 0.01; }
// The agents a fleet has beyond kCrowdedFleet of the free cells (at least 1).
int agents_past_crowded(const MapFacts& f) {
  const double crowd = kCrowdedFleet * static_cast<double>(f.free_cells());
  return std::max(1, f.num_agents() - static_cast<int>(std::floor(crowd + 1e-9)));
}

std::string rule_k_threshold(const std::string&, const MapFacts& f, const PlannerParams&) {
  return std::to_string(std::max(2, std::min(f.num_agents() / 10, 20)));
}
std::string rule_thousands(const std::string& param, const MapFacts& f, const PlannerParams&) {
  const bool big = thousands(f);
  if (param == "lg-lazy") return big ? "1" : "0";
  if (param == "lg-cost") return big ? "1.5" : "3";
  return big ? "2" : "0";  // lg-phases
}
std::string rule_forecast(const std::string&, const MapFacts& f, const PlannerParams&) {
  return !thousands(f) && many_cut_cells(f) ? "8" : "0";
}
// The step budget per agent from which auto is expected to plan over operations (it asks for
// PibtStep::kOpRoom times their first pass before PIBT's deadline). On warehouse_large's 10,000
// agents, every row computed beforehand as in the Start-Kit and the windowed LNS off (rule
// anytime-lns), it planned over operations at every step with 6 and 7 us an agent
// (docs/results.md, "Session 43"); 7 leaves a margin for a slower first pass. With the operations
// listed on two threads `gdrhcr_sim` held them from 3 us, but the Start-Kit at 3.7 us did not
// ("Session 44").
constexpr double kOperationsBudgetPerAgent = 7e-6;  // seconds
// Whether PIBT is expected to plan over operations: asked for, or auto with a step budget that
// leaves room for them (without one auto plans over cells).
bool operations_expected(const MapFacts& f, const PlannerParams& earlier) {
  const std::string& way = earlier.text("rotation-pibt");
  if (way != "auto") return way == "operations";
  const double budget = earlier.has("step-budget") ? earlier.real("step-budget") : 0;
  return budget > 0 && budget >= kOperationsBudgetPerAgent * f.num_agents();
}
// Where PIBT plans 3-action operations (EPIBT) in the rotation model when the step's time allows
// (auto): fleets filling more than 90% of the free cells, and fleets of thousands on maps with
// open areas beside their aisles (lanes.hpp), where a move along an open area costs 2 more when
// operations are expected (PIBT over cells loses with it).
std::string rule_operations(const std::string& param, const MapFacts& f, const PlannerParams& earlier) {
  const bool rotation = f.model() == ActionModel::kRotation;
  if (param == "rotation-pibt")
    return rotation && (crowded_fleet(f) || (thousands(f) && f.open_areas())) ? "auto" : "cells";
  return rotation && f.open_areas() && operations_expected(f, earlier) ? "2" : "0";  // open-cost
}
// Fleets filling more than 90% of the free cells: agents wait 500 steps before they set out for a
// dead end, and longer while no more wait than the fleet has agents beyond 90% of the free cells;
// in the rotation model the swap applies after 20 steps standing. Over cells (given) no agent
// retreats to let another pass and PIBT's configurations are carried out to the end, each the best
// of 16 runs.
std::string rule_crowded(const std::string& param, const MapFacts& f, const PlannerParams& earlier) {
  const bool crowded = crowded_fleet(f);
  const bool rotation = f.model() == ActionModel::kRotation;
  if (param == "rotation-commit") return crowded && rotation ? "1" : "0";
  if (param == "dead-end-wait") return crowded ? "500" : "0";
  if (param == "dead-end-parked") return crowded ? std::to_string(agents_past_crowded(f)) : "0";
  if (param == "rotation-starts") return crowded && rotation ? "16" : "1";
  return crowded && earlier.text("rotation-pibt") == "cells" ? "0" : "20";  // rotation-swap-wait
}
// Guidance off where its paths cannot be followed: a crowded fleet, and in the rotation model a
// fleet of thousands, whose lazily kept paths go stale in the jams of a long run.
std::string rule_guidance_off(const std::string&, const MapFacts& f, const PlannerParams&) {
  const bool off = crowded_fleet(f) || (f.model() == ActionModel::kRotation && thousands(f));
  return off ? "none" : "local";
}
std::string rule_window(const std::string&, const MapFacts& f, const PlannerParams&) {
  return thousands(f) || many_cut_cells(f) ? "20" : "30";
}
// One-way lanes (lanes.hpp) where turning round in a one-cell aisle costs two turns: the
// rotation model. In the mapf model a robot backs out of an aisle in one step.
std::string rule_lanes(const std::string& param, const MapFacts& f, const PlannerParams&) {
  if (param == "lanes")
    return f.model() == ActionModel::kRotation && (thousands(f) || crowded_fleet(f)) ? "lines" : "aisles";
  return f.model() == ActionModel::kRotation ? "2" : "0";
}
// The anytime windowed LNS (window_lns.hpp) in the rotation model where the fleet leaves room to
// go round: at most 30% of the free cells. Denser, single-agent replanning among the others' paths
// mostly fails, and the plans it does change turn agents back and forth from step to step
// (docs/results.md, "The product default's rules"). Not where PIBT is expected to plan over
// operations: their own search spends the rest of the budget, and the LNS's share of it (the
// planner beneath gets half) left auto too little room for them (docs/results.md, "Session 43").
constexpr double kLnsFleetShare = 0.3;
std::string rule_lns(const std::string&, const MapFacts& f, const PlannerParams& earlier) {
  const bool room = f.model() == ActionModel::kRotation && f.fleet_share() <= kLnsFleetShare;
  return room && !operations_expected(f, earlier) ? "10" : "0";
}
std::string rule_far_cost(const std::string&, const MapFacts&, const PlannerParams& earlier) {
  const bool forecast = earlier.text("guidance") == "local" && earlier.integer("lg-forecast") >= 2;
  return forecast ? "2" : "-1";
}

const char* kRulesFigure = "docs/results.md, The product default's rules: ";

}  // namespace

const std::vector<ParamRule>& param_rules() {
  static const std::vector<ParamRule> rules = {
      {"k-threshold", "the paper's min(floor(0.1 k), 20), floored at 2 so a lone agent stays on the primary solver",
       std::string(kRulesFigure) + "k-threshold", rule_k_threshold},
      {"fleet-of-thousands",
       "past 2,000 agents guidance is kept lazily (lg-lazy 1), updated in 2 phases of map bands, and a cheaper "
       "collision (lg-cost 1.5) lets lazy paths meet and be searched again",
       std::string(kRulesFigure) + "fleet-of-thousands", rule_thousands},
      {"motion-forecast",
       "8 steps on maps with at least 1% cut cells (dead ends, one-lane passages), where motion strays from guidance; "
       "none elsewhere or past 2,000 agents",
       std::string(kRulesFigure) + "motion-forecast", rule_forecast},
      {"operations",
       "rotation model, fleets holding more than 90% of the free cells and fleets of more than 2,000 agents on "
       "maps with open areas beside their aisles (lanes.hpp): PIBT plans over operations when the step budget "
       "leaves room for their search, else over cells (rotation-pibt auto; elsewhere cells); where operations are "
       "expected (given, or auto with a step budget of at least 7 us an agent) on a map with open areas a forward "
       "move along one costs 2 more (open-cost 2; elsewhere 0: over cells it loses)",
       std::string(kRulesFigure) + "operations", rule_operations},
      {"crowded-fleet",
       "fleets holding more than 90% of the free cells: agents wait 500 steps before they set out for a dead end "
       "(dead-end-wait 500), and longer while no more wait than the fleet has agents beyond 90% of the free cells "
       "(dead-end-parked); in the rotation model the swap applies after 20 steps standing; over cells (given) no "
       "agent retreats for another (rotation-swap-wait 0) and PIBT's configurations are carried out to the end "
       "(rotation-commit 1), each the best of 16 runs (rotation-starts 16)",
       std::string(kRulesFigure) + "crowded-fleet", rule_crowded},
      {"guidance-off",
       "PIBT alone moves (guidance none) where guidance paths cannot be followed: fleets holding more than 90% of "
       "the free cells, and in the rotation model fleets of more than 2,000 agents (lazy paths go stale in the jams "
       "of long runs)",
       std::string(kRulesFigure) + "guidance-off", rule_guidance_off},
      {"guidance-window",
       "30 steps on maps without many cut cells (head-on meetings in long aisles show up late), up to 2,000 agents; "
       "else 20",
       std::string(kRulesFigure) + "guidance-window", rule_window},
      {"lanes",
       "rotation model: a forward move against a one-way lane costs 2 more (lane-cost 2; lanes.hpp); the lanes are "
       "the map's one-cell aisles, and for fleets of more than 2,000 agents or holding more than 90% of the free "
       "cells every row and column one can travel along (lanes lines); mapf model: none",
       std::string(kRulesFigure) + "lanes", rule_lanes},
      {"anytime-lns",
       "rotation model, fleets holding at most 30% of the free cells, unless PIBT is expected to plan over operations "
       "(rule operations; their search spends the rest): the rest of the step budget improves a 10-step joint plan "
       "by LNS (lns-window 10); elsewhere off (0)",
       std::string(kRulesFigure) + "anytime-lns", rule_lns},
      {"far-cost", "where the motion forecast runs, conflicts lg-near-steps or more ahead cost 2; else as lg-cost (-1)",
       std::string(kRulesFigure) + "far-cost", rule_far_cost},
  };
  return rules;
}

namespace {

// ---------------------------------------------------------------------------------------------
// The table.
ParamSpec integer(std::string name, double min, double max, std::string value, std::string meaning,
                  std::string rule = "", std::string paper = "") {
  return {std::move(name), ParamType::kInt, min, max, {}, std::move(meaning), std::move(value), std::move(rule), std::move(paper)};
}
ParamSpec real(std::string name, double min, double max, std::string value, std::string meaning,
               std::string rule = "", std::string paper = "") {
  return {std::move(name), ParamType::kReal, min, max, {}, std::move(meaning), std::move(value), std::move(rule), std::move(paper)};
}
ParamSpec flag(std::string name, std::string value, std::string meaning, std::string paper = "",
               std::string rule = "") {
  return {std::move(name), ParamType::kFlag, 0, 1, {}, std::move(meaning), std::move(value), std::move(rule), std::move(paper)};
}
ParamSpec choice(std::string name, std::vector<std::string> choices, std::string value, std::string meaning,
                 std::string paper = "", std::string rule = "") {
  return {std::move(name), ParamType::kChoice, 0, 0, std::move(choices), std::move(meaning), std::move(value), std::move(rule),
          std::move(paper)};
}

constexpr double kBig = 1 << 30;

ParamSpec preset_row() {
  return choice("preset", {"default", "paper"}, "default",
                "default: the product configuration; paper: the paper's exact one (parameters given explicitly win)");
}

std::string fmt_number(double x);

// PIBT's techniques (the PIBT baseline and GD-RHCR's secondary solver). The paper's PIBT has no swap.
std::vector<ParamSpec> pibt_rows() {
  return {flag("swap", "1", "LaCAM*'s swap operation (in the rotation model see rotation-swap-wait)", "0"),
          choice("rotation-pibt", {"operations", "cells", "auto"}, "",
                 "rotation model: PIBT over 3-action operations carried on between steps (EPIBT; with a step "
                 "budget its LNS spends the rest), over cells chosen with turns counted and executed turning first, "
                 "or (auto) over operations when the step's time to its deadline is " +
                     fmt_number(PibtStep::kOpRoom) + " times their first pass (room for the search), else over cells",
                 "operations", "operations"),
          integer("rotation-swap-wait", 0, 1000, "",
                  "rotation model: the swap applies to an agent that has stood in its cell this many steps (0 = never)",
                  "crowded-fleet", "0"),
          flag("rotation-commit", "",
               "rotation model, cells: carry out each configuration PIBT chooses for the whole fleet (turns, then "
               "moves; agents that arrived wait) before planning the next", "0", "crowded-fleet"),
          integer("rotation-starts", 1, 1024, "",
                  "rotation model, with rotation-commit: each configuration is the best of this many PIBT runs, "
                  "each but the first with the priorities around a random agent shaken (the one bringing the agents "
                  "nearest their goals; no run past the step budget)",
                  "crowded-fleet", "1"),
          flag("rotation-keep", "1",
               "rotation model, cells: an agent that did not get to the cell PIBT chose for it (it turned towards "
               "it, or waited for the agent in it) tries that cell first at the next step, unless guidance gives "
               "it one", "0"),
          integer("rotation-push-turn-cost", 0, 64, "2",
                  "rotation model, cells, without rotation-commit: extra cost, for an agent pushed by another, of "
                  "a cell it must turn towards (it stays, and so does its pusher)",
                  "", "0"),
          integer("dead-end-wait", 0, 1000000, "",
                  "steps an agent whose goal is a dead end (one free neighbour) waits where it stands before it sets "
                  "out for it (0 = never)",
                  "crowded-fleet", "0"),
          integer("dead-end-parked", 0, 1000000, "",
                  "agents past their dead-end-wait keep waiting while no more than this many wait in all; beyond "
                  "it those past their wait set out, the longest-waiting first (0 = each when its wait ends)",
                  "crowded-fleet", "0"),
          flag("priority-reset", "1", "reset an agent's priority when it reaches a goal"),
          choice("tie-break", {"free-first", "random"}, "free-first",
                 "order among equally near cells: an unoccupied one first, or random"),
          real("traffic-cost", 0, 8, "0",
               "rotation model: extra cost of a forward move into the map's busiest cells (by sampled shortest-path "
               "flow), so distances lead around them (0 = none)"),
          real("lane-cost", 0, 8, "0",
               "rotation model: extra cost of a forward move against a one-way lane derived from the map (see lanes; "
               "0 = none)"),
          choice("lanes", {"aisles", "lines"}, "aisles",
                 "rotation model, with lane-cost: the one-way lanes are the map's one-cell aisles, or every row and "
                 "column one can travel along, alternating"),
          real("open-cost", 0, 8, "",
               "rotation model: extra cost of a forward move along an open area of a map with aisles (two or more "
               "open rows or columns side by side, such as the band before a warehouse's stations; see lanes), so "
               "distances travel in the aisles and cross the open areas (0 = none)",
               "operations", "0")};
}

// Local guidance (PIBT following windowed paths); `product` selects GD-RHCR's product defaults.
std::vector<ParamSpec> guidance_rows(bool product, const std::string& guidance_default) {
  return {
      choice("guidance", {"none", "local"}, guidance_default, "PIBT follows local guidance paths (local) or distances",
             product ? "none" : ""),
      integer("lg-forecast", 0, 1000, "0", "steps of the motion forecast guidance is planned around (0 = none, >= 2)",
              product ? "motion-forecast" : "", product ? "0" : ""),
      integer("lg-forecast-window", 1, 1000, "8", "guidance window of the forecast's rollout"),
      integer("lg-window", 1, 1000, "20", "steps each guidance path covers", product ? "guidance-window" : "",
              product ? "20" : ""),
      real("lg-cost", 0, 1e6, "", "cost of a conflict with another guidance path", "fleet-of-thousands"),
      flag("lg-cost-per-kind", "1", "the conflict cost is paid per kind of conflict (vertex, swap) a step meets"),
      real("lg-far-cost", -1, 1e6, "", "cost of a conflict lg-near-steps or more ahead (-1 = lg-cost)", "far-cost"),
      integer("lg-near-steps", 0, 1000, "3", "conflicts this many steps ahead or more cost lg-far-cost"),
      real("lg-contraflow", 0, 1e6, "0", "cost per guidance path planned the other way along an edge",
           "", ""),
      flag("lg-straight", "0",
           "mapf model: among equally cheap guidance paths the one with the fewest changes of direction (for robots "
           "that turn before a move, as under the ROS node)"),
      flag("lg-lazy", "", "keep guidance paths until they are left or meet another (fleets of thousands)", "",
           "fleet-of-thousands"),
      integer("lg-recheck", 0, 1000, "20", "a kept path is searched again if it meets another within this many steps"),
      integer("lg-keep", -1, 1000, "-1", "a kept path must still cover this many steps (-1 = lg-window / 2)"),
      integer("lg-expansions", 1, kBig, "4000", "node expansions per guidance search"),
      integer("lg-blocked-steps", -1, 1000, "-1", "steps a blocked cell counts as taken (-1 = lg-window)"),
      integer("lg-phases", 0, 1000, "", "0: one sequential guidance pass; P >= 2: P phases of map bands in parallel",
              "fleet-of-thousands"),
      integer("lg-refine", -1, 1000, "-1",
              "passes searching again the guidance paths that meet another, until the guidance deadline (-1 = 3 "
              "with a step budget, none without)",
              "", "0"),
  };
}

std::vector<ParamSpec> pibt_table() {
  std::vector<ParamSpec> t = {preset_row()};
  for (auto& r : pibt_rows()) t.push_back(r);
  for (auto& r : guidance_rows(false, "none")) t.push_back(r);
  return t;
}

std::vector<ParamSpec> rhcr_table() {
  return {preset_row(),
          integer("H", 1, 100000, "20", "planning window, steps"),
          integer("alpha", 1, 100000, "5", "replanning period, steps (<= H)"),
          real("timeout", 0, 1e9, "60", "seconds per PBS call (> 0)"),
          integer("node-budget", 0, 2000000000, "0", "PBS node limit per call, deterministic (0 = none)")};
}

std::vector<ParamSpec> gd_rhcr_table() {
  std::vector<ParamSpec> t = {
      preset_row(),
      integer("V", 0, 1 << 20, "2", "agents within this shortest-path distance plan together"),
      integer("H", 1, 100000, "20", "the primary solver's planning window, steps"),
      real("c-soft", 0, 1e9, "1", "cost of a conflict with another group's plan"),
      integer("k-threshold", 1, kBig, "", "groups this large go to the secondary solver", "k-threshold"),
      real("timeout", 0, 1e9, "60", "seconds per primary solve (> 0)"),
      real("step-budget", 0, 1e6, "0",
           "seconds per step (0 = none): solves get 60%, guidance refinement stops at 50%, guidance at 85%, PIBT at 95% (the agents it has not reached step ahead or wait)"),
      integer("node-budget", 0, 2000000000, "0", "PBS node limit per solve, deterministic (0 = none)"),
      integer("threads", 1, 1024, "1", "thread pool for the groups replanned in one step, zones of the windowed LNS searched at once, and halves of the map PIBT's search over operations improves at once"),
      choice("solver", {"pbs", "pibt"}, "pbs", "the primary solver"),
      real("max-density", 0, 1, "0.02",
           "groups with more than this share of the free cells around them occupied go to the secondary solver", "",
           "1"),
      integer("density-margin", 0, 1 << 20, "4", "cells around a group's bounding box counted for max-density"),
  };
  for (auto& r : pibt_rows()) t.push_back(r);
  // After PIBT's rows: rule anytime-lns reads the way PIBT plans.
  t.push_back(integer("lns-window", 0, 1000, "",
                      "steps of the joint plan the rest of the step budget improves by LNS (0 = off; window_lns.hpp)",
                      "anytime-lns", "0"));
  t.push_back(integer("lns-neighbours", 1, 1000, "8", "agents an LNS neighbourhood plans again together"));
  t.push_back(integer("lns-iterations", 0, 1000000, "0", "LNS neighbourhoods per step (0 = until the step budget)"));
  for (auto& r : guidance_rows(true, "local")) t.push_back(r);
  for (auto& r : t) {
    if (r.name == "lg-contraflow") r.value = "0.1", r.paper = "0";
    if (r.name == "lane-cost") r.rule = "lanes", r.paper = "0";
    if (r.name == "lanes") r.rule = "lanes", r.paper = "aisles";
    if (r.name == "guidance") r.rule = "guidance-off";
  }
  return t;
}

const std::map<std::string, std::vector<ParamSpec>>& tables() {
  static const std::map<std::string, std::vector<ParamSpec>> t = {
      {"pibt", pibt_table()}, {"rhcr", rhcr_table()}, {"gd-rhcr", gd_rhcr_table()}};
  return t;
}

const ParamRule& rule_named(const std::string& name) {
  for (auto& r : param_rules())
    if (r.name == name) return r;
  throw std::logic_error("planner parameter table: no rule " + name);
}

std::string fmt_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", x);
  return buf;
}

// Reads `spec` from `given` (checked and normalised) when present.
std::optional<std::string> read_given(Params& given, const ParamSpec& spec) {
  if (!given.has(spec.name)) {
    given.get_string(spec.name, "");  // mark it read: the planner has it
    return std::nullopt;
  }
  switch (spec.type) {
    case ParamType::kInt:
      return std::to_string(given.get_int(spec.name, 0, static_cast<int>(spec.min), static_cast<int>(spec.max)));
    case ParamType::kFlag: return std::to_string(given.get_int(spec.name, 0, 0, 1));
    case ParamType::kReal:
      given.get_double(spec.name, 0, spec.min, spec.max);  // checked; kept as written
      return given.get_string(spec.name, "");
    case ParamType::kChoice: return given.get_choice(spec.name, "", spec.choices);
  }
  return std::nullopt;
}

// Checks across parameters, each naming the parameter at fault.
void check_combinations(const PlannerParams& v) {
  if (v.has("timeout") && !(v.real("timeout") > 0)) throw ParamError("parameter timeout must be > 0 seconds");
  if (v.has("alpha") && v.integer("alpha") > v.integer("H"))
    throw ParamError("parameter alpha must be <= H (" + std::to_string(v.integer("H")) + ")");
  if (v.has("lg-phases") && v.integer("lg-phases") == 1)
    throw ParamError("parameter lg-phases must be 0 (sequential) or >= 2");
  if (v.has("lg-forecast") && v.integer("lg-forecast") == 1)
    throw ParamError("parameter lg-forecast must be 0 (none) or >= 2");
  if (v.has("lg-far-cost") && v.real("lg-far-cost") < 0 && v.real("lg-far-cost") != -1)
    throw ParamError("parameter lg-far-cost must be >= 0, or -1 (as lg-cost)");
}

}  // namespace

std::string ParamSpec::range_text() const {
  switch (type) {
    case ParamType::kFlag: return "0|1";
    case ParamType::kChoice: {
      std::string s;
      for (auto& c : choices) s += (s.empty() ? "" : "|") + c;
      return s;
    }
    case ParamType::kInt: return "[" + std::to_string(static_cast<long>(min)) + ", " + std::to_string(static_cast<long>(max)) + "]";
    default: return "[" + fmt_number(min) + ", " + fmt_number(max) + "]";
  }
}

const std::vector<ParamSpec>& planner_param_specs(const std::string& planner) {
  auto it = tables().find(planner);
  if (it != tables().end()) return it->second;
  std::string all;
  for (auto& [name, t] : tables()) all += (all.empty() ? "" : ", ") + name;
  throw ParamError("unknown planner '" + planner + "' (known: " + all + ")");
}

bool planner_has_param(const std::string& planner, const std::string& name) {
  const std::string key = Params::canonical(name);
  for (auto& s : planner_param_specs(planner))
    if (s.name == key) return true;
  return false;
}

PlannerParams PlannerParams::resolve(const std::string& planner, Params& given, const MapFacts& facts) {
  PlannerParams out;
  out.planner_ = planner;
  const auto& specs = planner_param_specs(planner);
  out.preset_ = given.get_choice("preset", "default", specs.front().choices);
  const bool paper = out.preset_ == "paper";
  out.values_.reserve(specs.size());
  for (const ParamSpec& spec : specs) {
    ParamValue v{&spec, "", ""};
    if (auto g = read_given(given, spec)) {
      v.text = *g, v.source = "given";
    } else if (paper && !spec.paper.empty()) {
      v.text = spec.paper, v.source = "paper";
    } else if (!spec.rule.empty()) {
      v.text = rule_named(spec.rule).pick(spec.name, facts, out), v.source = "rule " + spec.rule;
    } else {
      v.text = spec.value, v.source = "default";
    }
    out.values_.push_back(std::move(v));
  }
  check_combinations(out);
  return out;
}

const ParamValue* PlannerParams::find(const std::string& name) const {
  const std::string key = Params::canonical(name);
  for (auto& v : values_)
    if (v.spec->name == key) return &v;
  return nullptr;
}

const ParamValue& PlannerParams::at(const std::string& name) const {
  if (auto* v = find(name)) return *v;
  throw std::logic_error("planner " + planner_ + " has no parameter " + name + " (or it is not resolved yet)");
}

int PlannerParams::integer(const std::string& name) const { return std::atoi(at(name).text.c_str()); }
double PlannerParams::real(const std::string& name) const { return std::strtod(at(name).text.c_str(), nullptr); }
bool PlannerParams::flag(const std::string& name) const { return at(name).text == "1"; }
const std::string& PlannerParams::text(const std::string& name) const { return at(name).text; }

nlohmann::json PlannerParams::to_json() const {
  nlohmann::json j = nlohmann::json::object();
  for (auto& v : values_) {
    std::string key = v.spec->name;
    std::replace(key.begin(), key.end(), '-', '_');
    switch (v.spec->type) {
      case ParamType::kInt: j[key] = integer(v.spec->name); break;
      case ParamType::kReal: j[key] = real(v.spec->name); break;
      case ParamType::kFlag: j[key] = flag(v.spec->name); break;
      case ParamType::kChoice: j[key] = v.text; break;
    }
  }
  return j;
}

std::string PlannerParams::format() const {
  std::ostringstream out;
  char line[512];
  std::snprintf(line, sizeof line, "%-19s %-10s %-34s %-22s %s\n", "parameter", "value", "default", "range", "meaning");
  out << line;
  for (auto& v : values_) {
    const ParamSpec& s = *v.spec;
    std::string def = s.rule.empty() ? s.value : "rule " + s.rule;
    if (!s.paper.empty()) def += " (paper " + s.paper + ")";
    std::string value = v.text + (v.source == "given" ? " *" : "");
    std::snprintf(line, sizeof line, "%-19s %-10s %-34s %-22s %s\n", s.name.c_str(), value.c_str(), def.c_str(),
                  s.range_text().c_str(), s.meaning.c_str());
    out << line;
  }
  out << "(* given; the rest from the preset '" << preset_ << "'; rules:)\n";
  for (auto& r : param_rules()) out << "  " << r.name << ": " << r.why << "\n";
  return out.str();
}

StepCosts step_costs(const PlannerParams& values, ActionModel model) {
  StepCosts c;
  if (values.has("lanes") && values.text("lanes") == "lines") c.lane_style = LaneStyle::kLines;
  for (auto [name, value] :
       {std::pair{"traffic-cost", &c.traffic}, std::pair{"lane-cost", &c.lane}, std::pair{"open-cost", &c.open}}) {
    *value = values.has(name) ? values.real(name) : 0;
    if (*value > 0 && model != ActionModel::kRotation)
      throw ParamError(std::string("parameter ") + name + " applies to the rotation model only (got " +
                       fmt_number(*value) + ")");
  }
  return c;
}

}  // namespace gdrhcr
