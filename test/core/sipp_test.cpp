// SIPP: shortest paths without constraints, never a hard-constraint violation, optimal against
// a brute-force space-time search, goal sequences, and the soft-constraint trade-off.
#include <gtest/gtest.h>

#include <random>

#include "gdrhcr/sipp.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

int first_index(const std::vector<Cell>& p, Cell c) {
  for (size_t i = 0; i < p.size(); ++i)
    if (p[i] == c) return static_cast<int>(i);
  return -1;
}

void expect_valid_moves(const Grid& g, const std::vector<Cell>& p) {
  for (size_t t = 1; t < p.size(); ++t) ASSERT_TRUE(g.step_allowed(p[t - 1], p[t])) << t;
}

// Reference for one goal: layered space-time search over (cell, t, reached) for t <= H. The
// cost is the earliest time the agent is done (goal visited, then parked in a cell that stays
// free to H), or H + remaining distance when the goal is not visited by H.
int brute_force_cost(const Grid& g, const DistTable& dist, Cell s, Cell goal, const ConstraintTable& ct) {
  const int H = ct.horizon();
  const int n = g.num_cells();
  auto free_until_h = [&](Cell c, int t) {
    for (int u = t; u <= H; ++u)
      if (ct.vertex_blocked(c, u)) return false;
    return true;
  };
  std::vector<uint8_t> cur(2 * n, 0), nxt(2 * n, 0);
  if (ct.vertex_blocked(s, 0)) return -1;
  cur[2 * s + (s == goal)] = 1;
  for (int t = 0;; ++t) {
    for (Cell c = 0; c < n; ++c)
      if (cur[2 * c + 1] && free_until_h(c, t)) return t;
    if (t == H) {
      int best = -1;
      for (Cell c = 0; c < n; ++c)
        if (cur[2 * c] && (best < 0 || H + dist.get(goal, c) < best)) best = H + dist.get(goal, c);
      return best;
    }
    std::fill(nxt.begin(), nxt.end(), 0);
    for (Cell c = 0; c < n; ++c)
      for (int r = 0; r < 2; ++r) {
        if (!cur[2 * c + r]) continue;
        auto go = [&](Cell v) {
          if (ct.vertex_blocked(v, t + 1)) return;
          if (v != c && ct.move_blocked(c, v, t)) return;
          nxt[2 * v + (r || v == goal)] = 1;
        };
        go(c);
        for (Cell v : g.neighbours(c)) go(v);
      }
    std::swap(cur, nxt);
  }
}
}  // namespace

TEST(Sipp, UnconstrainedLengthsEqualBfsDistances) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist(g);
  std::mt19937_64 rng(7);
  const auto& fc = g.free_cells();
  Sipp sipp(g);
  for (int H : {5, 20, 80}) {
    ConstraintTable ct(g, H);
    int checked = 0;
    for (int k = 0; k < 300; ++k) {
      const Cell s = fc[rng() % fc.size()], goal = fc[rng() % fc.size()];
      const int d = dist.get(goal, s);
      SippResult r = sipp.plan(dist, s, {goal}, ct, nullptr, 0);
      if (d >= kUnreachable) continue;  // other component
      ASSERT_TRUE(r.found);
      ASSERT_EQ(r.path.front(), s);
      EXPECT_EQ(first_index(r.path, goal), d) << "H=" << H;
      EXPECT_EQ(r.cost, d);
      EXPECT_EQ(static_cast<int>(r.path.size()), std::max(H, d) + 1);
      if (d <= H) EXPECT_EQ(r.path.back(), goal);  // waits at its only goal
      expect_valid_moves(g, r.path);
      ++checked;
    }
    EXPECT_GT(checked, 200);
  }
}

TEST(Sipp, WaitsForAVertexConstraintInACorridor) {
  Grid g = Grid::from_rows({"....."});
  DistTable dist(g);
  ConstraintTable ct(g, 10);
  ct.block_vertex(g.cell(2, 0), 2);
  ct.block_vertex(g.cell(2, 0), 3);
  Sipp sipp(g);
  SippResult r = sipp.plan(dist, g.cell(0, 0), {g.cell(4, 0)}, ct, nullptr, 0);
  ASSERT_TRUE(r.found);
  EXPECT_EQ(first_index(r.path, g.cell(4, 0)), 6);  // two waits before (2,0)
  EXPECT_FALSE(ct.violated_by(r.path));
  EXPECT_EQ(r.path[1], g.cell(1, 0));  // waits in the safe interval of (1,0), not at the start
  EXPECT_EQ(r.path[3], g.cell(1, 0));
}

TEST(Sipp, AvoidsSwapsWithHigherPriorityPaths) {
  // A higher-priority agent walks the corridor towards us; we must dodge into the bay at (2,1).
  Grid g = Grid::from_rows({"........", "@@.@@@@@"});
  DistTable dist(g);
  ConstraintTable ct(g, 14);
  std::vector<Cell> other;
  for (int x = 7; x >= 0; --x) other.push_back(g.cell(x, 0));  // parks at (0,0), our start
  ct.add_path(other);
  Sipp sipp(g);
  SippResult r = sipp.plan(dist, g.cell(0, 0), {g.cell(7, 0)}, ct, nullptr, 0);
  ASSERT_TRUE(r.found);
  EXPECT_FALSE(ct.violated_by(r.path));
  EXPECT_EQ(r.path.back(), g.cell(7, 0));
  EXPECT_NE(first_index(r.path, g.cell(2, 1)), -1);
  EXPECT_EQ(first_index(r.path, g.cell(7, 0)), 11);  // in the bay at 3, out at 6, 5 more steps
  expect_valid_moves(g, r.path);
  for (size_t t = 0; t + 1 < other.size(); ++t) {
    EXPECT_FALSE(r.path[t] == other[t + 1] && r.path[t + 1] == other[t]) << t;
    EXPECT_NE(r.path[t], other[t]) << t;
  }

  // The other agent parked on our goal: we may only enter it once the window is over.
  ConstraintTable ct2(g, 10);
  ct2.add_path({g.cell(7, 0)});
  SippResult r2 = sipp.plan(dist, g.cell(0, 0), {g.cell(7, 0)}, ct2, nullptr, 0);
  ASSERT_TRUE(r2.found);
  EXPECT_FALSE(ct2.violated_by(r2.path));
  EXPECT_EQ(first_index(r2.path, g.cell(7, 0)), 11);

  // Trapped: the other agent comes down a dead end at us within the window. No path.
  Grid dead = Grid::from_rows({"...."});
  DistTable dd(dead);
  ConstraintTable ct3(dead, 6);
  ct3.add_path({dead.cell(3, 0), dead.cell(2, 0), dead.cell(1, 0), dead.cell(0, 0)});
  Sipp sipp_dead(dead);
  EXPECT_FALSE(sipp_dead.plan(dd, dead.cell(0, 0), {dead.cell(3, 0)}, ct3, nullptr, 0).found);
}

TEST(Sipp, NeverViolatesRandomHardConstraintsAndIsOptimal) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable dist(g);
  std::mt19937_64 rng(11);
  const auto& fc = g.free_cells();
  Sipp sipp(g);
  const int H = 12;
  ConstraintTable ct(g, H);
  int found = 0;
  for (int trial = 0; trial < 60; ++trial) {
    ct.clear();
    // 120 random walkers as higher-priority agents.
    for (int a = 0; a < 120; ++a) {
      std::vector<Cell> p = {fc[rng() % fc.size()]};
      for (int t = 0; t < H; ++t) {
        auto nb = g.neighbours(p.back());
        const int k = static_cast<int>(rng() % (nb.size() + 1));
        p.push_back(k == nb.size() ? p.back() : nb.begin()[k]);
      }
      ct.add_path(p);
    }
    Cell s, goal;
    do s = fc[rng() % fc.size()]; while (ct.vertex_blocked(s, 0));
    do goal = fc[rng() % fc.size()]; while (dist.get(goal, s) >= kUnreachable);
    SippResult r = sipp.plan(dist, s, {goal}, ct, nullptr, 0);
    const int ref = brute_force_cost(g, dist, s, goal, ct);
    if (ref < 0) {
      EXPECT_FALSE(r.found);
      continue;
    }
    ASSERT_TRUE(r.found) << trial;
    ++found;
    EXPECT_FALSE(ct.violated_by(r.path)) << trial;
    EXPECT_EQ(r.cost, ref) << trial;
    EXPECT_GE(static_cast<int>(r.path.size()), H + 1);
    EXPECT_NE(first_index(r.path, goal), -1);
    expect_valid_moves(g, r.path);
  }
  EXPECT_GT(found, 40);
}

TEST(Sipp, ContinuesToTheNextKnownGoal) {
  Grid g = Grid::from_rows({".........."});
  DistTable dist(g);
  ConstraintTable ct(g, 8);
  Sipp sipp(g);
  SippResult r = sipp.plan(dist, g.cell(3, 0), {g.cell(5, 0), g.cell(0, 0)}, ct, nullptr, 0);
  ASSERT_TRUE(r.found);
  ASSERT_EQ(r.path.size(), 9u);
  EXPECT_EQ(r.path[2], g.cell(5, 0));
  EXPECT_EQ(r.path[7], g.cell(0, 0));  // 2 + 5 steps
  EXPECT_EQ(r.path[8], g.cell(0, 0));  // then waits at the last known goal
  EXPECT_EQ(r.cost, 7);
}

TEST(Sipp, SoftConstraintsPreferConflictFreeEqualLengthPath) {
  Grid g = Grid::from_rows({"...", "...", "..."});
  DistTable dist(g);
  ConstraintTable ct(g, 6);
  SoftConstraintTable soft(g);
  soft.add_path({g.cell(2, 1), g.cell(1, 1), g.cell(1, 0), g.cell(0, 0)});
  Sipp sipp(g);
  for (double c : {0.01, 1.0, 100.0}) {
    SippResult r = sipp.plan(dist, g.cell(0, 0), {g.cell(2, 2)}, ct, &soft, c);
    ASSERT_TRUE(r.found);
    EXPECT_EQ(first_index(r.path, g.cell(2, 2)), 4) << c;
    EXPECT_EQ(r.soft_conflicts, 0) << c;
    EXPECT_EQ(count_soft_conflicts(r.path, soft, 6), 0);
  }
  // A swap counts as a conflict. On a line the soft agent comes (1,0) -> (0,0) and parks on our
  // start, so going straight through (one swap) beats waiting there.
  Grid line = Grid::from_rows({"..."});
  DistTable dl(line);
  ConstraintTable cl(line, 4);
  SoftConstraintTable sl(line);
  sl.add_path({line.cell(1, 0), line.cell(0, 0)});
  EXPECT_EQ(sl.edge_count(line.cell(0, 0), line.cell(1, 0), 0), 1);
  Sipp sipp_line(line);
  SippResult r = sipp_line.plan(dl, line.cell(0, 0), {line.cell(2, 0)}, cl, &sl, 0.5);
  ASSERT_TRUE(r.found);
  EXPECT_EQ(r.path[2], line.cell(2, 0));
  EXPECT_EQ(r.soft_conflicts, 1);
  EXPECT_DOUBLE_EQ(r.cost, 2.5);
  EXPECT_EQ(count_soft_conflicts(r.path, sl, 4), 1);
}

TEST(Sipp, SoftConstraintsTradeDetourAgainstCSoft) {
  // Direct route along the top row (4 steps) passes a parked agent at (2,0) once; the detour
  // along the bottom row takes 8 steps and is conflict-free. Waiting never helps (it stays).
  Grid g = Grid::from_rows({".....", ".@@@.", "....."});
  DistTable dist(g);
  ConstraintTable ct(g, 10);
  SoftConstraintTable soft(g);
  soft.add_path({g.cell(2, 0)});
  Sipp sipp(g);
  const Cell s = g.cell(0, 0), goal = g.cell(4, 0);
  struct Case { double c; int arrival; int conflicts; };
  for (Case k : {Case{0.0, 4, 1}, Case{1.0, 4, 1}, Case{3.9, 4, 1}, Case{4.0, 8, 0}, Case{5.0, 8, 0}}) {
    SippResult r = sipp.plan(dist, s, {goal}, ct, &soft, k.c);
    ASSERT_TRUE(r.found);
    EXPECT_EQ(first_index(r.path, goal), k.arrival) << "c_soft " << k.c;
    EXPECT_EQ(r.soft_conflicts, k.conflicts) << "c_soft " << k.c;
    EXPECT_DOUBLE_EQ(r.cost, k.arrival + k.c * k.conflicts);
  }
  // A crossing soft agent: waiting one step lets it pass, worth it once c_soft >= 1 (at 1 the
  // tie goes to fewer conflicts).
  Grid x = Grid::from_rows({"@.@", "...", "@.@"});
  DistTable dx(x);
  ConstraintTable cx(x, 6);
  SoftConstraintTable cross(x);
  cross.add_path({x.cell(1, 0), x.cell(1, 1), x.cell(1, 2)});
  Sipp sipp_x(x);
  for (Case k : {Case{0.5, 2, 1}, Case{1.0, 3, 0}, Case{2.0, 3, 0}}) {
    SippResult r = sipp_x.plan(dx, x.cell(0, 1), {x.cell(2, 1)}, cx, &cross, k.c);
    ASSERT_TRUE(r.found);
    EXPECT_EQ(first_index(r.path, x.cell(2, 1)), k.arrival) << "c_soft " << k.c;
    EXPECT_EQ(r.soft_conflicts, k.conflicts) << "c_soft " << k.c;
    EXPECT_EQ(count_soft_conflicts(r.path, cross, 6), k.conflicts);
  }
}

TEST(Sipp, ExpansionBudgetAndUnreachableGoal) {
  Grid g = Grid::from_rows({"...@...", "...@..."});
  DistTable dist(g);
  ConstraintTable ct(g, 5);
  Sipp sipp(g);
  // Goal in the other component: the agent just parks.
  SippResult r = sipp.plan(dist, g.cell(0, 0), {g.cell(6, 0)}, ct, nullptr, 0);
  ASSERT_TRUE(r.found);
  EXPECT_EQ(r.path.size(), 6u);
  EXPECT_EQ(r.path.back(), g.cell(0, 0));
  // One expansion is not enough to get past the 5-step horizon.
  SippLimits lim;
  lim.expansion_budget = 1;
  SippResult b = sipp.plan(dist, g.cell(0, 0), {g.cell(2, 1)}, ct, nullptr, 0, lim);
  EXPECT_FALSE(b.found);
  EXPECT_TRUE(b.cut_short);
  EXPECT_EQ(b.expansions, 1);
}
