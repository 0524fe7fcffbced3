// The parameter table (planner_params.hpp): every planner is built with the values the table
// resolves, the presets and the named rules pick what the README says, bad names and values are
// errors naming them, and the README lists every parameter.
#include <gtest/gtest.h>

#include <fstream>
#include <set>
#include <sstream>

#include "gdrhcr/planner.hpp"
#include "gdrhcr/planner_params.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

PlannerParams resolve(const std::string& planner, Params p, const Grid& g, int agents) {
  PlannerParams v = PlannerParams::resolve(planner, p, MapFacts(g, agents));
  p.check_all_used("test");
  return v;
}

// Every value the planner reports using that is a table parameter equals the table's value.
void expect_planner_uses_table(const std::string& planner, Params p, const Grid& g, int agents) {
  const PlannerParams values = resolve(planner, p, g, agents);
  Params again = p;
  const auto built = make_planner(planner, again, g, agents, 1)->params();
  const auto table = values.to_json();
  int compared = 0;
  for (auto& [key, value] : built.items()) {
    if (!table.contains(key)) continue;
    EXPECT_EQ(value, table[key]) << planner << " " << key;
    ++compared;
  }
  EXPECT_GE(compared, planner == "rhcr" ? 4 : 8) << planner;
}
}  // namespace

TEST(PlannerParams, PlannersAreBuiltWithTheTablesValues) {
  const Grid warehouse = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  const Grid random = Grid::load(repo("maps/random-32-32-20.map"));
  for (const std::string preset : {"default", "paper"})
    for (const std::string planner : planner_names())
      for (const Grid* g : {&warehouse, &random})
        for (int agents : {300, 2500}) {
          if (agents > static_cast<int>(g->free_cells().size())) continue;
          Params p;
          p.set("preset", preset);
          if (planner == "pibt") p.set("guidance", "local");
          expect_planner_uses_table(planner, p, *g, agents);
        }
}

TEST(PlannerParams, PresetsAndRulesPickTheDocumentedDefaults) {
  const Grid warehouse = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  const Grid random = Grid::load(repo("maps/random-32-32-20.map"));  // 2.8% cut cells
  auto value = [](const std::string& preset, const Grid& g, int agents, const std::string& name) {
    Params p;
    p.set("preset", preset);
    return resolve("gd-rhcr", p, g, agents).text(name);
  };
  EXPECT_EQ(value("default", warehouse, 400, "lg-window"), "30");
  EXPECT_EQ(value("default", random, 300, "lg-window"), "20");
  EXPECT_EQ(value("default", warehouse, 2500, "lg-window"), "20");
  EXPECT_EQ(value("paper", warehouse, 400, "lg-window"), "20");
  EXPECT_EQ(value("default", random, 300, "lg-forecast"), "8");
  EXPECT_EQ(value("default", warehouse, 400, "lg-forecast"), "0");
  EXPECT_EQ(value("paper", random, 300, "lg-forecast"), "0");
  EXPECT_EQ(value("default", random, 300, "lg-far-cost"), "2");
  EXPECT_EQ(value("default", warehouse, 400, "lg-far-cost"), "-1");
  EXPECT_EQ(value("default", warehouse, 2500, "lg-lazy"), "1");
  EXPECT_EQ(value("default", warehouse, 400, "lg-lazy"), "0");
  EXPECT_EQ(value("default", warehouse, 2500, "lg-cost"), "1.5");
  EXPECT_EQ(value("default", warehouse, 2500, "lg-phases"), "2");
  EXPECT_EQ(value("default", warehouse, 400, "k-threshold"), "20");
  EXPECT_EQ(value("default", warehouse, 15, "k-threshold"), "2");
  EXPECT_EQ(value("default", warehouse, 400, "guidance"), "local");
  EXPECT_EQ(value("paper", warehouse, 400, "guidance"), "none");
  EXPECT_EQ(value("paper", warehouse, 400, "max-density"), "1");
  EXPECT_EQ(value("paper", warehouse, 400, "swap"), "0");
  EXPECT_EQ(value("paper", warehouse, 400, "lg-contraflow"), "0");
  EXPECT_EQ(value("default", warehouse, 400, "lg-contraflow"), "0.1");
  // Rule lanes: one-way lanes in the rotation model only; the paper has none.
  auto lane = [&](const std::string& preset, ActionModel model) {
    Params p;
    p.set("preset", preset);
    PlannerParams v = PlannerParams::resolve("gd-rhcr", p, MapFacts(warehouse, 400, model));
    return std::pair{v.text("lane-cost"), step_costs(v, model).lane};
  };
  EXPECT_EQ(lane("default", ActionModel::kRotation), std::pair(std::string("2"), 2.0));
  EXPECT_EQ(lane("default", ActionModel::kMapf), std::pair(std::string("0"), 0.0));
  EXPECT_EQ(lane("paper", ActionModel::kRotation), std::pair(std::string("0"), 0.0));
  // ... on the aisles, and on every row and column for a fleet of thousands.
  auto lines = [&](const std::string& preset, int agents) {
    Params p;
    p.set("preset", preset);
    PlannerParams v = PlannerParams::resolve("gd-rhcr", p, MapFacts(warehouse, agents, ActionModel::kRotation));
    return std::pair{v.text("lanes"), step_costs(v, ActionModel::kRotation).lane_style == LaneStyle::kLines};
  };
  EXPECT_EQ(lines("default", 400), std::pair(std::string("aisles"), false));
  EXPECT_EQ(lines("default", 2500), std::pair(std::string("lines"), true));
  EXPECT_EQ(lines("paper", 2500), std::pair(std::string("aisles"), false));
  // A map without aisles gets them too, for a fleet of thousands in the rotation model only.
  Params none;
  EXPECT_EQ(PlannerParams::resolve("gd-rhcr", none, MapFacts(random, 2500, ActionModel::kRotation)).text("lanes"),
            "lines");
  EXPECT_EQ(PlannerParams::resolve("gd-rhcr", none, MapFacts(random, 2500, ActionModel::kMapf)).text("lanes"),
            "aisles");
  // And a crowded fleet (over 90% of the free cells) of any size.
  const int crowd = int(random.free_cells().size()) * 95 / 100;
  EXPECT_EQ(PlannerParams::resolve("gd-rhcr", none, MapFacts(random, crowd, ActionModel::kRotation)).text("lanes"),
            "lines");
  EXPECT_EQ(PlannerParams::resolve("gd-rhcr", none, MapFacts(random, crowd * 8 / 10, ActionModel::kRotation))
                .text("lanes"),
            "aisles");
  // Rule guidance-off: a crowded fleet (over 90% of the free cells) in either model, and a fleet of
  // thousands in the rotation model only; the paper has no guidance.
  auto guidance = [&](const std::string& preset, int agents, ActionModel model) {
    Params p;
    p.set("preset", preset);
    const PlannerParams v = PlannerParams::resolve("gd-rhcr", p, MapFacts(warehouse, agents, model));
    for (auto& x : v.values())
      if (x.spec->name == "guidance" && preset == "default") EXPECT_EQ(x.source, "rule guidance-off");
    return v.text("guidance");
  };
  const int free = int(warehouse.free_cells().size());
  EXPECT_EQ(guidance("default", 2500, ActionModel::kRotation), "none");
  EXPECT_EQ(guidance("default", 2000, ActionModel::kRotation), "local");
  EXPECT_EQ(guidance("default", 2500, ActionModel::kMapf), "local");
  EXPECT_EQ(guidance("default", free * 95 / 100, ActionModel::kMapf), "none");
  EXPECT_EQ(guidance("paper", 2500, ActionModel::kMapf), "none");
  // Rule crowded-fleet: over 90% of the free cells dead ends wait 500 steps, and longer while no
  // more wait than the fleet has agents beyond 90% of the free cells; in the rotation model PIBT
  // plans over operations when the budget leaves room for their search (auto), with the swap after
  // 20 steps standing; over cells (given) its configurations are carried out to the end and nobody
  // swaps. Not below, not in the paper.
  auto crowded = [&](const std::string& preset, int agents, ActionModel model, const char* way = nullptr) {
    Params p;
    p.set("preset", preset);
    if (way) p.set("rotation-pibt", way);
    const PlannerParams v = PlannerParams::resolve("gd-rhcr", p, MapFacts(warehouse, agents, model));
    return std::tuple{v.text("rotation-pibt"), v.integer("rotation-swap-wait"), v.flag("rotation-commit"),
                      v.integer("dead-end-wait"), v.integer("dead-end-parked")};
  };
  const int full = free * 95 / 100, less = free * 85 / 100;
  const int past = full - free * 9 / 10;  // agents beyond 90% of the free cells
  ASSERT_GT(past, 1);
  EXPECT_EQ(crowded("default", full, ActionModel::kRotation), std::tuple("auto", 20, true, 500, past));
  EXPECT_EQ(crowded("default", full, ActionModel::kRotation, "operations"),
            std::tuple("operations", 20, true, 500, past));
  EXPECT_EQ(crowded("default", full, ActionModel::kRotation, "cells"), std::tuple("cells", 0, true, 500, past));
  EXPECT_EQ(crowded("default", less, ActionModel::kRotation), std::tuple("cells", 20, false, 0, 0));
  EXPECT_EQ(crowded("default", full, ActionModel::kMapf), std::tuple("cells", 0, false, 500, past));
  EXPECT_EQ(crowded("paper", full, ActionModel::kRotation), std::tuple("operations", 0, false, 0, 0));
  // Rule operations: fleets of thousands on maps with open areas beside their aisles (lanes.hpp)
  // plan over operations in the rotation model when the budget allows (auto), with a move along an
  // open area 2 dearer when operations are expected (given, or auto with a step budget of 7 us an
  // agent or more, whatever the threads); not over cells, not below 2,000 agents, not in the mapf
  // model or the paper, not on maps without open areas. Rule anytime-lns: where operations are expected their search
  // spends the rest of the budget, and the windowed LNS is off.
  const Grid banded = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/lorr-warehouse-140-500.map");
  auto operations = [&](const Grid& map, const std::string& preset, ActionModel model, const char* way = nullptr,
                        const char* budget = "0.1", const char* threads = nullptr) {
    Params p;
    p.set("preset", preset);
    p.set("step-budget", budget);
    if (threads) p.set("threads", threads);
    if (way) p.set("rotation-pibt", way);
    const PlannerParams v = PlannerParams::resolve("gd-rhcr", p, MapFacts(map, 3000, model));
    return std::tuple{v.text("rotation-pibt"), v.real("open-cost"), v.integer("lns-window")};
  };
  using Way = std::tuple<std::string, double, int>;
  Params none_given;
  const PlannerParams small = PlannerParams::resolve("gd-rhcr", none_given, MapFacts(banded, 1500, ActionModel::kRotation));
  EXPECT_EQ(std::pair(small.text("rotation-pibt"), small.real("open-cost")), std::pair(std::string("cells"), 0.0));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation), Way("auto", 2.0, 0));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation, nullptr, "0.022"), Way("auto", 2.0, 0));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation, nullptr, "0.020"), Way("auto", 0.0, 10));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation, nullptr, "0.022", "2"), Way("auto", 2.0, 0));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation, nullptr, "0.020", "2"), Way("auto", 0.0, 10));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation, nullptr, "0"), Way("auto", 0.0, 10));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation, "operations"), Way("operations", 2.0, 0));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation, "operations", "0"), Way("operations", 2.0, 0));
  EXPECT_EQ(operations(banded, "default", ActionModel::kRotation, "cells"), Way("cells", 0.0, 10));
  EXPECT_EQ(operations(banded, "default", ActionModel::kMapf), Way("cells", 0.0, 0));
  EXPECT_EQ(operations(banded, "paper", ActionModel::kRotation), Way("operations", 0.0, 0));
  EXPECT_EQ(operations(warehouse, "default", ActionModel::kRotation), Way("cells", 0.0, 0));
  Params given;
  const PlannerParams sparse = PlannerParams::resolve("gd-rhcr", given, MapFacts(random, 300, ActionModel::kRotation));
  EXPECT_EQ(std::pair(sparse.text("rotation-pibt"), sparse.real("open-cost")), std::pair(std::string("cells"), 0.0));
  // Given values win over the preset and the rules, and say so.
  Params p;
  p.set("preset", "paper");
  p.set("lg_window", "12");
  const PlannerParams v = resolve("gd-rhcr", p, warehouse, 400);
  EXPECT_EQ(v.integer("lg-window"), 12);
  for (auto& x : v.values())
    if (x.spec->name == "lg-window") EXPECT_EQ(x.source, "given");
}

TEST(PlannerParams, UnknownAndOutOfRangeParametersAreErrorsNamingThem) {
  const Grid g = Grid::from_rows({"....", "....", "...."});
  auto message = [&](const std::string& planner, const std::string& key, const std::string& value) {
    Params p;
    p.set(key, value);
    try {
      make_planner(planner, p, g, 4, 1);
    } catch (const ParamError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_NE(message("gd-rhcr", "lg_windwo", "3").find("lg-windwo"), std::string::npos);
  EXPECT_NE(message("pibt", "V", "3").find("V"), std::string::npos);  // PIBT has no V
  EXPECT_NE(message("gd-rhcr", "max_density", "1.5").find("max-density must be in [0, 1]"), std::string::npos);
  EXPECT_NE(message("gd-rhcr", "solver", "cbs").find("solver must be one of pbs, pibt"), std::string::npos);
  EXPECT_NE(message("gd-rhcr", "lg-phases", "1").find("lg-phases"), std::string::npos);
  EXPECT_NE(message("gd-rhcr", "lg-far-cost", "-0.5").find("lg-far-cost"), std::string::npos);
  EXPECT_NE(message("gd-rhcr", "swap", "2").find("swap must be in [0, 1]"), std::string::npos);
  EXPECT_NE(message("gd-rhcr", "preset", "fast").find("preset must be one of default, paper"), std::string::npos);
  EXPECT_NE(message("gd-rhcr", "lane-cost", "9").find("lane-cost must be in [0, 8]"), std::string::npos);
  for (const char* cost : {"lane-cost", "traffic-cost"}) {  // step costs outside the rotation model
    Params p;
    p.set(cost, "1");
    const PlannerParams v = PlannerParams::resolve("gd-rhcr", p, MapFacts(g, 4));
    try {
      step_costs(v, ActionModel::kMapf);
      ADD_FAILURE() << cost << " accepted in the mapf model";
    } catch (const ParamError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string(cost) + " applies to the rotation model only"),
                std::string::npos);
    }
  }
  // Experiments that were not kept are gone.
  for (const char* gone : {"secondary-stay", "solver2", "lg-keep-optimal", "lg-refresh"})
    EXPECT_NE(message("gd-rhcr", gone, "1").find(gone), std::string::npos) << gone;
  EXPECT_NE(message("pibt", "tie-break", "hindrance").find("tie-break must be one of"), std::string::npos);
  EXPECT_THROW(planner_param_specs("astar"), ParamError);
  EXPECT_TRUE(planner_has_param("gd-rhcr", "K_threshold"));
  EXPECT_TRUE(planner_has_param("gd-rhcr", "c_soft"));
  EXPECT_FALSE(planner_has_param("gd-rhcr", "alpha"));
  EXPECT_TRUE(planner_has_param("rhcr", "alpha"));
}

// The README's parameter list names every parameter of every planner, and nothing else.
TEST(PlannerParams, TheReadmeListsEveryParameter) {
  std::ifstream in(repo("README.md"));
  std::stringstream text;
  text << in.rdbuf();
  const std::string readme = text.str();
  const auto begin = readme.find("<!-- planner parameters -->");
  const auto end = readme.find("<!-- /planner parameters -->");
  ASSERT_NE(begin, std::string::npos);
  ASSERT_NE(end, std::string::npos);
  const std::string section = readme.substr(begin, end - begin);
  std::set<std::string> listed, known;
  for (size_t at = section.find("`--"); at != std::string::npos; at = section.find("`--", at + 1)) {
    const size_t stop = section.find_first_of(" `", at + 3);
    listed.insert(section.substr(at + 3, stop - at - 3));
  }
  for (auto& planner : planner_names())
    for (auto& s : planner_param_specs(planner)) known.insert(s.name);
  for (auto& name : known) EXPECT_TRUE(listed.count(name)) << "README does not list --" << name;
  for (auto& name : listed) EXPECT_TRUE(known.count(name)) << "README lists --" << name << ", no planner has it";
}
