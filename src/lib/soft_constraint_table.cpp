// Soft constraint table: see soft_constraint_table.hpp. GD-RHCR (DeWeese, Li, Qu), soft
// constraints of cost c_soft for the other groups' plans.
#include "gdrhcr/soft_constraint_table.hpp"

namespace gdrhcr {

SoftConstraintTable::SoftConstraintTable(const Grid& grid) : head_(grid.num_cells(), -1) {}

void SoftConstraintTable::add_path(const std::vector<Cell>& path) {
  if (path.empty()) return;
  ++paths_;
  const int last = static_cast<int>(path.size()) - 1;
  for (int t = 0; t <= last; ++t) {
    const Cell c = path[t];
    if (head_[c] < 0) touched_.push_back(c);
    entries_.push_back({t, t < last ? path[t + 1] : kNoCell, head_[c]});
    head_[c] = static_cast<int32_t>(entries_.size()) - 1;
  }
}

int SoftConstraintTable::vertex_count(Cell c, int t) const {
  int n = 0;
  for (int32_t e = head_[c]; e >= 0; e = entries_[e].link) {
    const Entry& x = entries_[e];
    // The end entry stands for every time from t on (the agent stays parked).
    n += (x.t == t) || (x.next == kNoCell && x.t < t);
  }
  return n;
}

int SoftConstraintTable::edge_count(Cell from, Cell to, int t) const {
  if (from == to) return 0;
  int n = 0;
  for (int32_t e = head_[to]; e >= 0; e = entries_[e].link)
    n += entries_[e].t == t && entries_[e].next == from;
  return n;
}

void SoftConstraintTable::add_vertex_counts(Cell c, int t_max, int* counts) const {
  for (int32_t e = head_[c]; e >= 0; e = entries_[e].link) {
    const Entry& x = entries_[e];
    if (x.next == kNoCell) {
      for (int t = x.t; t <= t_max; ++t) ++counts[t];
    } else if (x.t <= t_max) {
      ++counts[x.t];
    }
  }
}

void SoftConstraintTable::clear() {
  for (Cell c : touched_) head_[c] = -1;
  touched_.clear();
  entries_.clear();
  paths_ = 0;
}

}  // namespace gdrhcr
