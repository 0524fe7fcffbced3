// PBS: collision-free windows on crowded small instances (checked pair by pair, independently of
// the solver's own scanner), paths that start right and reach their goals, determinism under a
// node budget, and soft constraints passed through to SIPP.
#include <gtest/gtest.h>

#include <random>

#include "gdrhcr/pbs.hpp"
#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

Cell at(const std::vector<Cell>& p, int t) { return p[std::min<size_t>(t, p.size() - 1)]; }

// Brute-force pairwise check: vertex collisions at t <= H and swaps departing t < H.
void expect_collision_free(const std::vector<std::vector<Cell>>& paths, int H) {
  for (size_t a = 0; a < paths.size(); ++a)
    for (size_t b = a + 1; b < paths.size(); ++b)
      for (int t = 0; t <= H; ++t) {
        ASSERT_NE(at(paths[a], t), at(paths[b], t)) << "vertex " << a << " " << b << " t=" << t;
        if (t < H)
          ASSERT_FALSE(at(paths[a], t) == at(paths[b], t + 1) && at(paths[a], t + 1) == at(paths[b], t))
              << "swap " << a << " " << b << " t=" << t;
      }
}

void expect_well_formed(const Grid& g, const DistTable& dist, const std::vector<Cell>& starts,
                        const std::vector<std::vector<Cell>>& goals, const PbsResult& r, int H) {
  ASSERT_EQ(r.paths.size(), starts.size());
  for (size_t k = 0; k < starts.size(); ++k) {
    const auto& p = r.paths[k];
    ASSERT_GE(static_cast<int>(p.size()), H + 1);
    EXPECT_EQ(p[0], starts[k]);
    for (size_t t = 1; t < p.size(); ++t) ASSERT_TRUE(g.step_allowed(p[t - 1], p[t]));
    if (dist.get(goals[k][0], starts[k]) < kUnreachable)
      EXPECT_NE(std::find(p.begin(), p.end(), goals[k][0]), p.end()) << k;
  }
}

struct Instance {
  std::vector<Cell> starts;
  std::vector<std::vector<Cell>> goals;
};

Instance random_instance(const Grid& g, int n, uint64_t seed, int lookahead = 2) {
  Instance in;
  in.starts = random_starts(g, n, seed);
  RandomNavigationStream tasks(g, seed + 100);
  for (int k = 0; k < n; ++k) {
    std::vector<Cell> seq;
    Cell last = in.starts[k];
    for (int j = 0; j < lookahead; ++j) seq.push_back(last = tasks.next_goal(k, last));
    in.goals.push_back(seq);
  }
  return in;
}
}  // namespace

TEST(Pbs, CrowdedSmallInstancesAreCollisionFreeInTheWindow) {
  Grid g = Grid::from_rows({"........", "........", "..@@....", "........", "....@@..", "........",
                            "........", "........"});
  DistTable dist(g);
  PbsConfig cfg;
  cfg.horizon = 10;
  cfg.node_budget = 5000;
  int solved = 0;
  for (uint64_t seed = 1; seed <= 40; ++seed) {
    Instance in = random_instance(g, 16, seed);  // a quarter of the cells
    cfg.backjump = seed % 2 == 0;                // plain PBS and PBS with backjumping
    PbsResult r = solve_pbs(g, dist, in.starts, in.goals, nullptr, cfg);
    EXPECT_LE(r.nodes, cfg.node_budget);
    if (!r.success) {
      EXPECT_TRUE(r.paths.empty());
      continue;
    }
    ++solved;
    expect_well_formed(g, dist, in.starts, in.goals, r, cfg.horizon);
    expect_collision_free(r.paths, cfg.horizon);
    EXPECT_EQ(first_collision(g, r.paths, cfg.horizon).t, -1);
  }
  EXPECT_GE(solved, 30);
}

TEST(Pbs, RandomMapManyAgents) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist(g);
  PbsConfig cfg;
  cfg.horizon = 20;
  cfg.node_budget = 3000;
  int solved = 0;
  for (uint64_t seed = 1; seed <= 5; ++seed) {
    Instance in = random_instance(g, 100, seed, 3);
    PbsResult r = solve_pbs(g, dist, in.starts, in.goals, nullptr, cfg);
    if (!r.success) continue;
    ++solved;
    EXPECT_GE(r.sipp_calls, 100);
    expect_well_formed(g, dist, in.starts, in.goals, r, cfg.horizon);
    expect_collision_free(r.paths, cfg.horizon);
  }
  EXPECT_GE(solved, 4);
}

TEST(Pbs, HeadOnInACorridorWithABay) {
  Grid g = Grid::from_rows({"........", "@@@.@@@@"});
  DistTable dist(g);
  std::vector<Cell> starts = {g.cell(0, 0), g.cell(7, 0)};
  std::vector<std::vector<Cell>> goals = {{g.cell(7, 0)}, {g.cell(0, 0)}};
  PbsConfig cfg;
  cfg.horizon = 16;
  cfg.node_budget = 100;
  PbsResult r = solve_pbs(g, dist, starts, goals, nullptr, cfg);
  ASSERT_TRUE(r.success);
  expect_well_formed(g, dist, starts, goals, r, cfg.horizon);
  expect_collision_free(r.paths, cfg.horizon);
  EXPECT_EQ(r.paths[0].back(), g.cell(7, 0));
  EXPECT_EQ(r.paths[1].back(), g.cell(0, 0));
  EXPECT_GE(r.nodes, 2);  // the root collides
}

TEST(Pbs, NodeBudgetIsDeterministicAndReported) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist(g);
  Instance in = random_instance(g, 250, 3, 3);
  PbsConfig cfg;
  cfg.node_budget = 5;
  PbsResult a = solve_pbs(g, dist, in.starts, in.goals, nullptr, cfg);
  PbsResult b = solve_pbs(g, dist, in.starts, in.goals, nullptr, cfg);
  EXPECT_EQ(a.success, b.success);
  EXPECT_EQ(a.nodes, b.nodes);
  EXPECT_EQ(a.sipp_calls, b.sipp_calls);
  EXPECT_EQ(a.paths, b.paths);
  if (!a.success) {
    EXPECT_TRUE(a.timed_out);
    EXPECT_LE(a.nodes, cfg.node_budget + 1);
  }
  // An unsatisfiable instance (two agents on one start) fails without timing out.
  PbsConfig cfg2;
  cfg2.node_budget = 1000;
  PbsResult c = solve_pbs(g, dist, {in.starts[0], in.starts[0]}, {in.goals[0], in.goals[1]}, nullptr, cfg2);
  EXPECT_FALSE(c.success);
  EXPECT_FALSE(c.timed_out);
}

TEST(Pbs, SoftConstraintsAreAvoidedWhenCheap) {
  // The corridor (row 0) is soft-blocked by a parked agent of another group at (3,0); a detour
  // along row 2 costs 4 more steps. c_soft = 10 takes the detour, c_soft = 1 goes through.
  Grid g = Grid::from_rows({".......", ".@@@@@.", "......."});
  DistTable dist(g);
  SoftConstraintTable soft(g);
  soft.add_path({g.cell(3, 0)});
  std::vector<Cell> starts = {g.cell(0, 0)};
  std::vector<std::vector<Cell>> goals = {{g.cell(6, 0)}};
  PbsConfig cfg;
  cfg.horizon = 12;
  cfg.c_soft = 10;
  PbsResult r = solve_pbs(g, dist, starts, goals, &soft, cfg);
  ASSERT_TRUE(r.success);
  EXPECT_EQ(r.soft_conflicts, 0);
  EXPECT_EQ(std::find(r.paths[0].begin(), r.paths[0].end(), g.cell(6, 0)) - r.paths[0].begin(), 10);
  cfg.c_soft = 1;
  r = solve_pbs(g, dist, starts, goals, &soft, cfg);
  ASSERT_TRUE(r.success);
  EXPECT_EQ(r.soft_conflicts, 1);
  EXPECT_EQ(r.paths[0][6], g.cell(6, 0));
}
