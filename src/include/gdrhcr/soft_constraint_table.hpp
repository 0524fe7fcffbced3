// Soft constraints: other agents' planned paths, as occupancy counts over (cell, time) and
// (edge, time), for a low-level search that pays for conflicts instead of forbidding them.
// GD-RHCR, DeWeese, Li, Qu, "A Theoretical Framework for Parallel Lifelong MAPF Using Group
// Decentralized Planning" (section "Soft Constraints"): a group is planned against the other
// groups' plans, every conflict with them costing c_soft.
//
// Time is relative: t = 0 is now, path[t] is the cell at time t. Beyond the end of a path the
// agent is taken to stay at its last cell forever (a parked robot keeps occupying its cell).
//
// Layout: one singly linked list of entries per cell, stored in one flat vector. Building costs
// O(total path length) plus one O(cells) head array at construction; `clear` is O(entries), so
// one table can be refilled every step. Const methods only read: concurrent reads are safe.
#pragma once

#include <cstdint>
#include <vector>

#include "gdrhcr/grid.hpp"

namespace gdrhcr {

class SoftConstraintTable {
 public:
  explicit SoftConstraintTable(const Grid& grid);

  // Adds one agent's path; path[t] is its cell at time t. An empty path adds nothing.
  void add_path(const std::vector<Cell>& path);
  // Agents at cell c at time t (t >= 0).
  int vertex_count(Cell c, int t) const;
  // Agents moving to -> from between t and t+1, i.e. the ones a move from -> to at t would swap
  // with. Staying agents never count.
  int edge_count(Cell from, Cell to, int t) const;
  // counts[t] += vertex_count(c, t) for t in [0, t_max], in one pass over c's entries.
  void add_vertex_counts(Cell c, int t_max, int* counts) const;
  // False when no path ever touches c (the common case, checked first by searches).
  bool touches(Cell c) const { return head_[c] >= 0; }

  void clear();
  bool empty() const { return paths_ == 0; }
  int num_paths() const { return paths_; }

 private:
  struct Entry {
    int32_t t;     // time of the visit
    Cell next;     // cell at t+1; kNoCell at the path's end (the agent stays from t on)
    int32_t link;  // next entry of the same cell, -1 at the end
  };
  std::vector<int32_t> head_;  // per cell: first entry, -1 if none
  std::vector<Entry> entries_;
  std::vector<Cell> touched_;  // cells with a non-empty list, for an O(entries) clear
  int paths_ = 0;
};

}  // namespace gdrhcr
