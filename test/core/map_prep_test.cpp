// Offline preparation (map_prep.hpp): trials on the map pick the traffic cost by the goals they
// reach, the file is keyed by the map, and a file for another map, fleet or model, or no
// preparation file at all, is refused with the reason.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include "gdrhcr/map_prep.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

std::string refusal(const std::string& path, const Grid& g, int agents, ActionModel model) {
  try {
    load_prep(path, g, agents, model);
  } catch (const PrepError& e) {
    return e.what();
  }
  return "accepted";
}

bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }
}  // namespace

TEST(MapPrep, TheKeyFollowsTheMapsCells) {
  const Grid a = Grid::from_rows({"....", ".@..", "...."});
  const Grid same = Grid::from_rows({"....", ".@..", "...."});
  const Grid moved = Grid::from_rows({"....", "..@.", "...."});
  const Grid wider = Grid::from_rows({".....", ".@...", "....."});
  EXPECT_EQ(map_key(a), map_key(same));
  EXPECT_NE(map_key(a), map_key(moved));
  EXPECT_NE(map_key(a), map_key(wider));
  EXPECT_EQ(map_key(a).size(), 16u);
}

TEST(MapPrep, TrialsPickTheCostThatReachesMostGoalsAndTheFileRoundTrips) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  PrepOptions o;
  o.agents = 60;
  o.steps = 60;
  o.step_budget_s = 0;  // deterministic
  const MapPrep p = prepare_map(g, o);
  ASSERT_EQ(p.trials.size(), 6u);  // 3 candidates (0, 1, 2) x 2 seeds
  for (auto& t : p.trials) EXPECT_GT(t.goals, 0);
  EXPECT_EQ(p.trials[1].seed, o.seed + 1);
  const long none = p.trials[0].goals + p.trials[1].goals, one = p.trials[2].goals + p.trials[3].goals,
             two = p.trials[4].goals + p.trials[5].goals;
  EXPECT_EQ(p.goals_of(0), none);
  EXPECT_EQ(p.goals_of(1), one);
  EXPECT_EQ(p.goals_of(2), two);
  EXPECT_NE(p.trials[0].goals, p.trials[1].goals);  // two seeds, two runs
  // The most goals wins, if it beats none by the margin; else none.
  double expected = 0;
  for (auto [k, goals] : {std::pair{1.0, one}, std::pair{2.0, two}})
    if (goals > p.goals_of(expected) && goals > (1 + MapPrep::kMargin) * none) expected = k;
  EXPECT_EQ(p.traffic_cost, expected);
  EXPECT_EQ(prepare_map(g, o).trials[5].goals, p.trials[5].goals);  // a seed fixes the trials

  const std::string path = testing::TempDir() + "/prep_roundtrip.json";
  save_prep(p, path);
  const MapPrep back = load_prep(path, g, 60, ActionModel::kRotation);
  EXPECT_EQ(back.to_json(), p.to_json());

  Params given;
  EXPECT_EQ(back.apply(given), 1);
  EXPECT_EQ(given.get_double("traffic-cost", -1, 0, 8), p.traffic_cost);
  Params set;
  set.set("traffic_cost", "1");
  EXPECT_EQ(back.apply(set), 0);  // a given value wins
  EXPECT_EQ(set.get_double("traffic-cost", -1, 0, 8), 1.0);

  const Grid other = Grid::load(repo("maps/room-32-32-4.map"));
  EXPECT_TRUE(contains(refusal(path, other, 60, ActionModel::kRotation), "was made for another map")) << refusal(path, other, 60, ActionModel::kRotation);
  EXPECT_TRUE(contains(refusal(path, g, 61, ActionModel::kRotation), "was made for 60 agents, not 61"));
  EXPECT_TRUE(contains(refusal(path, g, 60, ActionModel::kMapf), "rotation action model, not mapf"));
  EXPECT_TRUE(contains(refusal(path + ".missing", g, 60, ActionModel::kRotation), "cannot read"));
  std::ofstream(path) << "{\"format\": \"something else\"}\n";
  EXPECT_TRUE(contains(refusal(path, g, 60, ActionModel::kRotation), "not a preparation file"));
  std::ofstream(path) << "{\"format\": \"gdrhcr-prep/2\", \"map_key\": 3";
  EXPECT_TRUE(contains(refusal(path, g, 60, ActionModel::kRotation), path));
  nlohmann::json bad = p.to_json();
  bad["traffic_cost"] = 50;
  std::ofstream(path) << bad.dump();
  EXPECT_TRUE(contains(refusal(path, g, 60, ActionModel::kRotation), "traffic_cost 50 is not in [0, 8]"));
  std::remove(path.c_str());
}

// A crowded fleet (rule crowded-fleet: more than 90% of the free cells, here 14 agents on 15
// cells) runs each candidate on each seed, as any fleet does.
TEST(MapPrep, ACrowdedFleetTriesEveryCandidate) {
  const Grid g = Grid::from_rows({".....", ".....", "....."});
  PrepOptions o;
  o.agents = 14;
  o.steps = 10;
  o.step_budget_s = 0;
  const MapPrep p = prepare_map(g, o);
  ASSERT_EQ(p.trials.size(), o.traffic_costs.size() * size_t(o.seeds));
  for (size_t k = 0; k < p.trials.size(); ++k) EXPECT_EQ(p.trials[k].traffic_cost, o.traffic_costs[k / o.seeds]);
}

// With a time limit the first trial stops at its share of it (here after its first step) and
// the others run as many steps.
TEST(MapPrep, ATimeLimitShortensTheTrials) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  PrepOptions o;
  o.agents = 20;
  o.steps = 400;
  o.time_limit_s = 1e-9;
  const MapPrep p = prepare_map(g, o);
  EXPECT_EQ(p.steps, 1);
  ASSERT_EQ(p.trials.size(), o.traffic_costs.size() * size_t(o.seeds));
  for (auto& t : p.trials) EXPECT_EQ(t.steps, 1);
  o.time_limit_s = 1e6;
  EXPECT_EQ(prepare_map(g, o).steps, 400);
}

TEST(MapPrep, BadOptionsAreErrorsNamingThem) {
  const Grid g = Grid::from_rows({"....", "....", "...."});
  PrepOptions o;
  o.agents = 4;
  o.steps = 5;
  o.model = ActionModel::kMapf;
  EXPECT_THROW(prepare_map(g, o), ParamError);
  o.model = ActionModel::kRotation;
  o.agents = 13;
  try {
    prepare_map(g, o);
    ADD_FAILURE() << "13 agents on 12 cells accepted";
  } catch (const ParamError& e) {
    EXPECT_TRUE(contains(e.what(), "agents must be in [1, 12]"));
  }
  o.agents = 4;
  o.given.set("lg-windwo", "3");
  try {
    prepare_map(g, o);
    ADD_FAILURE() << "an unknown parameter accepted";
  } catch (const ParamError& e) {
    EXPECT_TRUE(contains(e.what(), "lg-windwo"));
  }
}
