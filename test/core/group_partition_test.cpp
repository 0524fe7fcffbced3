// Groups equal the connected components of "shortest-path distance <= V", checked against a
// brute force over all pairs on random instances, including walls where Manhattan misleads.
#include <gtest/gtest.h>

#include <random>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/group_partition.hpp"
#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

// Brute force: all pairs, distances from the BFS table, components by repeated flooding.
std::vector<std::vector<int>> brute_force(const Grid& g, const std::vector<Cell>& pos, int V) {
  DistTable dist(g);
  const int n = static_cast<int>(pos.size());
  std::vector<int> comp(n, -1);
  std::vector<std::vector<int>> groups;
  for (int s = 0; s < n; ++s) {
    if (comp[s] >= 0) continue;
    groups.push_back({});
    std::vector<int> stack = {s};
    comp[s] = static_cast<int>(groups.size()) - 1;
    while (!stack.empty()) {
      int a = stack.back();
      stack.pop_back();
      groups.back().push_back(a);
      for (int b = 0; b < n; ++b)
        if (comp[b] < 0 && dist.get(pos[a], pos[b]) <= V) {
          comp[b] = comp[s];
          stack.push_back(b);
        }
    }
    std::sort(groups.back().begin(), groups.back().end());
  }
  return groups;  // ordered by smallest member, like GroupPartition
}
}  // namespace

TEST(GroupPartition, WallSeparatesManhattanNeighbours) {
  // Agents at (0,0) and (2,0) are 2 apart by Manhattan distance but 6 apart around the wall.
  Grid g = Grid::from_rows({".@...", ".@...", "....."});
  GroupPartition p(g);
  std::vector<Cell> pos = {g.cell(0, 0), g.cell(2, 0)};
  p.compute(pos, 2);
  EXPECT_EQ(p.groups().size(), 2u);
  p.compute(pos, 5);
  EXPECT_EQ(p.groups().size(), 2u);
  p.compute(pos, 6);
  EXPECT_EQ(p.groups().size(), 1u);
}

TEST(GroupPartition, TransitiveChains) {
  Grid g = Grid::from_rows({"........."});
  GroupPartition p(g);
  // 0 -2- 1 -2- 2 ... 3 is 3 away from 2: chain {0,1,2}, singleton {3}.
  std::vector<Cell> pos = {g.cell(0, 0), g.cell(2, 0), g.cell(4, 0), g.cell(7, 0)};
  p.compute(pos, 2);
  ASSERT_EQ(p.groups().size(), 2u);
  EXPECT_EQ(p.groups()[0], (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(p.groups()[1], (std::vector<int>{3}));
  EXPECT_EQ(p.group_of(2), 0);
  EXPECT_EQ(p.group_of(3), 1);
  p.compute(pos, 0);  // V = 0: everyone alone
  EXPECT_EQ(p.groups().size(), 4u);
}

TEST(GroupPartition, MatchesBruteForceOnRandomInstances) {
  for (const char* file : {"maps/random-32-32-20.map", "maps/room-32-32-4.map", "maps/warehouse-10-20-10-2-1.map"}) {
    Grid g = Grid::load(repo(file));
    GroupPartition p(g);
    for (uint64_t seed = 1; seed <= 4; ++seed) {
      for (int V : {0, 1, 2, 3, 5}) {
        auto pos = random_starts(g, 60 + 40 * static_cast<int>(seed), seed * 31 + V);
        p.compute(pos, V);
        EXPECT_EQ(p.groups(), brute_force(g, pos, V)) << file << " seed " << seed << " V " << V;
      }
    }
  }
}

TEST(GroupPartition, RecomputeReusesBuffersCorrectly) {
  Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  GroupPartition p(g);
  for (uint64_t s = 0; s < 50; ++s) {
    auto pos = random_starts(g, 100, s);
    p.compute(pos, 2);
    size_t total = 0;
    for (auto& grp : p.groups()) total += grp.size();
    EXPECT_EQ(total, 100u);
  }
}

namespace {
// Rotation brute force: i and j are linked when either reaches the other's cell by at most V
// actions (forward, a quarter turn either way), every sequence of them tried.
bool reaches(const Grid& g, Pose from, Cell to, int V) {
  if (from.cell == to) return true;
  if (V == 0) return false;
  for (Action a : {Action::kForward, Action::kClockwise, Action::kCounterClockwise}) {
    const Pose q = apply_action(g, from, a);
    if (q.cell != kNoCell && reaches(g, q, to, V - 1)) return true;
  }
  return false;
}

std::vector<std::vector<int>> brute_force_rotation(const Grid& g, const std::vector<Cell>& pos,
                                                   const std::vector<Heading>& heads, int V) {
  const int n = static_cast<int>(pos.size());
  UnionFind uf;
  uf.reset(n);
  for (int a = 0; a < n; ++a)
    for (int b = 0; b < n; ++b)
      if (a != b && reaches(g, {pos[a], heads[a]}, pos[b], V)) uf.unite(a, b);
  std::vector<std::vector<int>> groups;
  std::vector<int> index(n, -1);
  for (int i = 0; i < n; ++i) {
    const int r = uf.find(i);
    if (index[r] < 0) index[r] = static_cast<int>(groups.size()), groups.emplace_back();
    groups[index[r]].push_back(i);
  }
  return groups;
}
}  // namespace

TEST(GroupPartition, RotationMatchesBruteForceOnRandomInstances) {
  // V <= 2 takes a shortcut (the cells ahead and to either side); V >= 3 searches the states.
  for (const char* file : {"maps/random-32-32-20.map", "maps/room-32-32-4.map"}) {
    const Grid g = Grid::load(repo(file));
    GroupPartition p(g);
    for (uint64_t seed = 1; seed <= 3; ++seed) {
      for (int V : {0, 1, 2, 3}) {
        const auto pos = random_starts(g, 150 + 50 * static_cast<int>(seed), seed * 17 + V);
        std::mt19937_64 rng(seed + V);
        std::vector<Heading> heads(pos.size());
        for (auto& h : heads) h = static_cast<Heading>(rng() % 4);
        p.compute(pos, heads, V);
        EXPECT_EQ(p.groups(), brute_force_rotation(g, pos, heads, V)) << file << " seed " << seed << " V " << V;
      }
    }
  }
}
