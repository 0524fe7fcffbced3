// Params: validation messages name the parameter, and the paper's/ROS's spellings (c_soft,
// K_threshold, node_budget) are the same parameters as the command line's (c-soft, ...).
#include <gtest/gtest.h>

#include "gdrhcr/params.hpp"
#include "gdrhcr/planner.hpp"

using namespace gdrhcr;

TEST(Params, UnderscoreAndCaseSpellingsNameTheSameParameter) {
  EXPECT_EQ(Params::canonical("c_soft"), "c-soft");
  EXPECT_EQ(Params::canonical("K_threshold"), "k-threshold");
  EXPECT_EQ(Params::canonical("node_budget"), "node-budget");
  EXPECT_EQ(Params::canonical("V"), "V");  // one-letter names keep their case
  EXPECT_EQ(Params::canonical("H"), "H");
  Params p;
  p.set("K_threshold", "7");
  p.set("c_soft", "2.5");
  EXPECT_TRUE(p.has("k-threshold"));
  EXPECT_EQ(p.get_int("k-threshold", 0, 1, 100), 7);
  EXPECT_DOUBLE_EQ(p.get_double("c-soft", 1.0, 0, 10), 2.5);
  EXPECT_TRUE(p.unused().empty());
}

TEST(Params, GdRhcrAcceptsThePaperSpellingsAndRejectsBadValuesByName) {
  Grid g = Grid::from_rows({"....", "....", "...."});
  Params ok;
  ok.set("K_threshold", "3");
  ok.set("c_soft", "0.5");
  ok.set("node_budget", "100");
  auto planner = make_planner("gd-rhcr", ok, g, 4, 1);
  EXPECT_TRUE(ok.unused().empty());
  EXPECT_EQ(planner->params()["k_threshold"], 3);
  Params bad;
  bad.set("c_soft", "-1");
  try {
    make_planner("gd-rhcr", bad, g, 4, 1);
    FAIL() << "negative c_soft accepted";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("c-soft"), std::string::npos) << e.what();
  }
  Params typo;
  typo.set("c_sotf", "1");
  try {
    make_planner("gd-rhcr", typo, g, 4, 1);
    FAIL() << "misspelt c_sotf accepted";
  } catch (const ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("c-sotf"), std::string::npos) << e.what();
  }
}
