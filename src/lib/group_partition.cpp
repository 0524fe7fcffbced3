#include "gdrhcr/group_partition.hpp"

#include <numeric>

namespace gdrhcr {

void UnionFind::reset(int n) {
  parent_.resize(n);
  std::iota(parent_.begin(), parent_.end(), 0);
  rank_.assign(n, 0);
}

int UnionFind::find(int a) {
  while (parent_[a] != a) {
    parent_[a] = parent_[parent_[a]];  // path halving
    a = parent_[a];
  }
  return a;
}

void UnionFind::unite(int a, int b) {
  a = find(a);
  b = find(b);
  if (a == b) return;
  if (rank_[a] < rank_[b]) std::swap(a, b);
  parent_[b] = a;
  if (rank_[a] == rank_[b]) ++rank_[a];
}

GroupPartition::GroupPartition(const Grid& grid)
    : grid_(grid), agent_at_(grid.num_cells(), -1), seen_stamp_(grid.num_cells(), 0) {}

void GroupPartition::compute(const std::vector<Cell>& positions, int V) {
  const int n = static_cast<int>(positions.size());
  uf_.reset(n);
  for (int i = 0; i < n; ++i) agent_at_[positions[i]] = i;
  for (int i = 0; i < n; ++i) {
    // BFS of depth V from agent i; linking to agents with a larger id is enough, since the
    // distance is symmetric and the other direction is found from the smaller id.
    if (++stamp_ == 0) {  // stamp wrapped: clear the marks once
      std::fill(seen_stamp_.begin(), seen_stamp_.end(), 0);
      std::fill(state_stamp_.begin(), state_stamp_.end(), 0);
      stamp_ = 1;
    }
    frontier_.clear();
    frontier_.emplace_back(positions[i], 0);
    seen_stamp_[positions[i]] = stamp_;
    for (size_t head = 0; head < frontier_.size(); ++head) {
      auto [c, d] = frontier_[head];
      const int j = agent_at_[c];
      if (j > i) uf_.unite(i, j);
      if (d == V) continue;
      for (Cell nb : grid_.neighbours(c)) {
        if (seen_stamp_[nb] == stamp_) continue;
        seen_stamp_[nb] = stamp_;
        frontier_.emplace_back(nb, d + 1);
      }
    }
  }
  for (int i = 0; i < n; ++i) agent_at_[positions[i]] = -1;
  build_groups(n);
}

// Rotation: BFS of depth V over (cell, heading) states from agent i's state, linking i to every
// agent whose cell it reaches.
void GroupPartition::link_from_state(int i, Pose start, int V) {
  if (++stamp_ == 0) {  // stamp wrapped: clear both kinds of marks once
    std::fill(state_stamp_.begin(), state_stamp_.end(), 0);
    std::fill(seen_stamp_.begin(), seen_stamp_.end(), 0);
    stamp_ = 1;
  }
  state_frontier_.clear();
  state_frontier_.push_back({start, 0});
  state_stamp_[size_t(start.cell) * 4 + start.heading] = stamp_;
  for (size_t head = 0; head < state_frontier_.size(); ++head) {
    const StateStep s = state_frontier_[head];
    const int j = agent_at_[s.pose.cell];
    if (j >= 0 && j != i) uf_.unite(i, j);
    if (s.d == V) continue;
    for (Action a : {Action::kForward, Action::kClockwise, Action::kCounterClockwise}) {
      const Pose q = apply_action(grid_, s.pose, a);
      if (q.cell == kNoCell) continue;
      unsigned& mark = state_stamp_[size_t(q.cell) * 4 + q.heading];
      if (mark == stamp_) continue;
      mark = stamp_;
      state_frontier_.push_back({q, s.d + 1});
    }
  }
}

// The same for V <= 2 without the search: within two steps an agent reaches the cells ahead of it
// (two, through the first), and those on either side (a quarter turn, then forward).
void GroupPartition::link_near_state(int i, Pose start, int V) {
  auto link = [&](Cell c) {
    if (c == kNoCell) return;
    const int j = agent_at_[c];
    if (j >= 0 && j != i) uf_.unite(i, j);
  };
  if (V < 1) return;
  const Cell ahead = forward_cell(grid_, start.cell, start.heading);
  link(ahead);
  if (V < 2) return;
  if (ahead != kNoCell) link(forward_cell(grid_, ahead, start.heading));
  link(forward_cell(grid_, start.cell, rotate_cw(start.heading)));
  link(forward_cell(grid_, start.cell, rotate_ccw(start.heading)));
}

void GroupPartition::compute(const std::vector<Cell>& positions, const std::vector<Heading>& headings, int V) {
  const int n = static_cast<int>(positions.size());
  uf_.reset(n);
  state_stamp_.resize(size_t(grid_.num_cells()) * 4, 0);
  for (int i = 0; i < n; ++i) agent_at_[positions[i]] = i;
  for (int i = 0; i < n; ++i) {
    if (V <= 2) link_near_state(i, {positions[i], headings[i]}, V);
    else link_from_state(i, {positions[i], headings[i]}, V);
  }
  for (int i = 0; i < n; ++i) agent_at_[positions[i]] = -1;
  build_groups(n);
}

// Canonical order: iterating agents ascending makes each group's first agent its smallest.
// The group vectors are reused from the last call (thousands of groups a step).
void GroupPartition::build_groups(int n) {
  group_of_.assign(n, -1);
  index_of_root_.assign(n, -1);
  size_t count = 0;
  for (int i = 0; i < n; ++i) {
    const int r = uf_.find(i);
    if (index_of_root_[r] < 0) {
      index_of_root_[r] = static_cast<int>(count);
      if (count == groups_.size()) groups_.emplace_back();
      groups_[count++].clear();
    }
    group_of_[i] = index_of_root_[r];
    groups_[index_of_root_[r]].push_back(i);
  }
  groups_.resize(count);
}

}  // namespace gdrhcr
