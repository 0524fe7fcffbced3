// Group decentralization (DeWeese, Li, Qu, "A Theoretical Framework for Parallel Lifelong MAPF
// Using Group Decentralized Planning", Definition "group decentralization" and Algorithm 1,
// line 3): agents are linked when their shortest-path distance through the map is at most V,
// and groups are the connected components of that graph (union-find).
//
// Cost: one BFS of depth V from every agent, so O(agents x |V-ball|), never agents squared.
// Distances run through free cells; other agents do not block them.
//
// Rotation model (issue 23): distances count turns. The BFS runs over (cell, heading) states from
// each agent's own state (forward, or a quarter turn, one step each), and an agent is linked to
// every agent whose cell it reaches within V steps in any heading (that distance is not symmetric,
// so both directions link).
#pragma once

#include "gdrhcr/action_model.hpp"

#include <vector>

#include "gdrhcr/grid.hpp"

namespace gdrhcr {

class UnionFind {
 public:
  void reset(int n);
  int find(int a);
  void unite(int a, int b);

 private:
  std::vector<int> parent_, rank_;
};

class GroupPartition {
 public:
  explicit GroupPartition(const Grid& grid);

  // Recomputes the groups for agents at `positions` (distinct cells) with visibility V >= 0.
  void compute(const std::vector<Cell>& positions, int V);
  // The same in the rotation model: `headings` per agent (see above).
  void compute(const std::vector<Cell>& positions, const std::vector<Heading>& headings, int V);

  // Groups in a canonical order: each group's agents ascending, groups by their smallest agent.
  const std::vector<std::vector<int>>& groups() const { return groups_; }
  int group_of(int agent) const { return group_of_[agent]; }

 private:
  const Grid& grid_;
  UnionFind uf_;
  std::vector<int> agent_at_;        // agent per cell, -1 when empty
  std::vector<int> index_of_root_;   // build_groups: group per union-find root
  std::vector<unsigned> seen_stamp_;  // BFS visited marks, valid when equal to stamp_
  unsigned stamp_ = 0;
  std::vector<std::pair<Cell, int>> frontier_;
  std::vector<unsigned> state_stamp_;  // rotation: visited marks per (cell, heading)
  struct StateStep {
    Pose pose;
    int d;
  };
  std::vector<StateStep> state_frontier_;
  void link_from_state(int i, Pose start, int V);
  void link_near_state(int i, Pose start, int V);
  void build_groups(int n);
  std::vector<std::vector<int>> groups_;
  std::vector<int> group_of_;
};

}  // namespace gdrhcr
