// The solvers inside RHCR and GD-RHCR in the rotation model (issue 23): SIPP over (cell, heading)
// states, PBS with headings, and GD-RHCR's groups with turns counted.
#include <gtest/gtest.h>

#include "gdrhcr/group_partition.hpp"
#include "gdrhcr/local_guidance.hpp"
#include "gdrhcr/pbs.hpp"
#include "gdrhcr/sipp.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

// Every step of a path with headings is one action of the rotation model.
void expect_actions(const Grid& g, const std::vector<Cell>& p, const std::vector<Heading>& h) {
  ASSERT_EQ(p.size(), h.size());
  for (size_t t = 1; t < p.size(); ++t)
    ASSERT_TRUE(action_between(g, {p[t - 1], h[t - 1]}, {p[t], h[t]}))
        << "t " << t << ": " << g.describe(p[t - 1]) << " " << int(h[t - 1]) << " -> " << g.describe(p[t]) << " "
        << int(h[t]);
}

int arrival(const std::vector<Cell>& p, Cell goal) {
  for (size_t t = 0; t < p.size(); ++t)
    if (p[t] == goal) return static_cast<int>(t);
  return -1;
}
}  // namespace

TEST(RotationSipp, TurnsBeforeItMovesAndArrivesAtTheTurnCountedDistance) {
  const Grid g = Grid::from_rows({".....", "....."});
  DistTable dist(g, ActionModel::kRotation);
  ConstraintTable hard(g, 10);
  Sipp sipp(g);
  const SippAgent agent(dist, g.cell(0, 0), {g.cell(4, 0)}, 10, kWest);
  const SippResult r = sipp.plan(agent, hard, nullptr, 0);
  ASSERT_TRUE(r.found);
  expect_actions(g, r.path, r.headings);
  EXPECT_EQ(arrival(r.path, g.cell(4, 0)), 6);  // two turns, four moves
  EXPECT_EQ(r.headings[0], kWest);
}

TEST(RotationSipp, AvoidsHardConstraintsAndMatchesTheRowWhenFree) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist(g, ActionModel::kRotation);
  ConstraintTable hard(g, 30);
  Sipp sipp(g);
  const auto& free = g.free_cells();
  for (int k = 0; k < 20; ++k) {
    const Cell s = free[(k * 131 + 7) % free.size()], goal = free[(k * 577 + 101) % free.size()];
    const Heading h = static_cast<Heading>(k % 4);
    hard.clear();
    const SippResult r = sipp.plan(SippAgent(dist, s, {goal}, 30, h), hard, nullptr, 0);
    ASSERT_TRUE(r.found);
    expect_actions(g, r.path, r.headings);
    EXPECT_EQ(arrival(r.path, goal), dist.get(goal, s, h));
    // Block the cell at the time it planned to pass it (or the goal at arrival): a new plan
    // avoids it and is no shorter.
    const int t_mid = std::max(1, arrival(r.path, goal) / 2);
    hard.block_vertex(r.path[t_mid], t_mid);
    const SippResult r2 = sipp.plan(SippAgent(dist, s, {goal}, 30, h), hard, nullptr, 0);
    ASSERT_TRUE(r2.found);
    expect_actions(g, r2.path, r2.headings);
    EXPECT_FALSE(hard.violated_by(r2.path));
    EXPECT_GE(arrival(r2.path, goal), arrival(r.path, goal));
  }
}

TEST(RotationPbs, HeadOnAgentsPassInAValidPlan) {
  // A corridor with a bay: agents facing each other must let one another pass.
  const Grid g = Grid::from_rows({"......", "..@@@."});
  DistTable dist(g, ActionModel::kRotation);
  const std::vector<Cell> starts{g.cell(0, 0), g.cell(5, 0)};
  const std::vector<std::vector<Cell>> goals{{g.cell(5, 0)}, {g.cell(0, 0)}};
  const std::vector<Heading> heads{kEast, kWest};
  PbsConfig pc;
  pc.horizon = 20;
  pc.start_headings = &heads;
  const PbsResult r = solve_pbs(g, dist, starts, goals, nullptr, pc);
  ASSERT_TRUE(r.success);
  ASSERT_EQ(r.headings.size(), 2u);
  EXPECT_EQ(first_collision(g, r.paths, pc.horizon).t, -1);
  StepValidator v(g, ActionModel::kRotation);
  for (int t = 0; t < pc.horizon; ++t) {
    const std::vector<Cell> a{r.paths[0][t], r.paths[1][t]}, b{r.paths[0][t + 1], r.paths[1][t + 1]};
    const std::vector<Heading> ha{r.headings[0][t], r.headings[1][t]}, hb{r.headings[0][t + 1], r.headings[1][t + 1]};
    const auto bad = v.check(a, b, &ha, &hb);
    EXPECT_FALSE(bad) << bad->describe(g, t);
  }
  EXPECT_GE(arrival(r.paths[0], g.cell(5, 0)), 5);
  EXPECT_GE(arrival(r.paths[1], g.cell(0, 0)), 5);
}

TEST(RotationGroups, TurnsCountInTheVisibility) {
  const Grid g = Grid::from_rows({"...", "..."});
  GroupPartition part(g);
  const std::vector<Cell> pos{g.cell(0, 0), g.cell(1, 0)};
  // Neighbours: linked at V = 1 when one faces the other, not when both face away.
  part.compute(pos, std::vector<Heading>{kEast, kNorth}, 1);
  EXPECT_EQ(part.groups().size(), 1u);
  part.compute(pos, std::vector<Heading>{kWest, kEast}, 1);
  EXPECT_EQ(part.groups().size(), 2u);
  part.compute(pos, std::vector<Heading>{kWest, kEast}, 3);  // turn, turn, forward
  EXPECT_EQ(part.groups().size(), 1u);
  part.compute(pos, 1);  // mapf: neighbours are always linked
  EXPECT_EQ(part.groups().size(), 1u);
}

TEST(RotationGuidance, PathsTurnInPlaceAndTheNextMoveLooksPastTheTurn) {
  const Grid g = Grid::from_rows({"......", "......"});
  DistTable dist(g, ActionModel::kRotation);
  const std::vector<Cell> pos{g.cell(1, 0)};
  const std::vector<std::vector<Cell>> goals{{g.cell(5, 0)}};
  const std::vector<Heading> heads{kWest};
  std::vector<Heading> next_heads(1, kNoHeading);
  WorldView w{g, dist, 0, pos, goals};
  w.action_model = ActionModel::kRotation;
  w.headings = &heads;
  w.next_headings = &next_heads;
  LocalGuidanceConfig cfg;
  cfg.window = 10;
  LocalGuidance lg(g, 1, cfg);
  lg.update(w, {0});
  const auto path = lg.path_from(0, 0);
  // Facing away: two turns in place, then four moves east (the mapf path would leave at once).
  ASSERT_EQ(path.size(), 7u);
  EXPECT_EQ(path[1], g.cell(1, 0));
  EXPECT_EQ(path[2], g.cell(1, 0));
  EXPECT_EQ(path[3], g.cell(2, 0));
  EXPECT_EQ(path.back(), g.cell(5, 0));
  EXPECT_EQ(lg.next_cell(0, 0, pos[0]), g.cell(1, 0));
  EXPECT_EQ(lg.next_move(0, 0, pos[0]), g.cell(2, 0));
}
