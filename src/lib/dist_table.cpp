#include "gdrhcr/dist_table.hpp"

#include <algorithm>
#include <stdexcept>

namespace gdrhcr {

DistRow::DistRow(const Grid& grid, Cell goal, const std::vector<uint8_t>* blocked)
    : goal_(goal), dist_(grid.num_cells(), kUnreachable) {
  std::vector<Cell> queue;
  queue.reserve(grid.free_cells().size());
  dist_[goal] = 0;
  queue.push_back(goal);
  for (size_t head = 0; head < queue.size(); ++head) {
    const Cell c = queue[head];
    const int32_t d = dist_[c] + 1;
    for (Cell n : grid.neighbours(c)) {
      if (dist_[n] != kUnreachable || (blocked && (*blocked)[n])) continue;
      dist_[n] = d;
      queue.push_back(n);
    }
  }
}

DistTable::DistTable(const Grid& grid, size_t budget_bytes) : grid_(grid), budget_(budget_bytes) {}

DistTable::DistTable(const Grid& grid, const std::vector<Cell>& blocked, size_t budget_bytes)
    : grid_(grid), budget_(budget_bytes) {
  if (blocked.empty()) return;
  blocked_.assign(grid.num_cells(), 0);
  for (Cell c : blocked)
    if (grid.valid_cell(c)) blocked_[c] = 1;
}

std::shared_ptr<const DistRow> DistTable::row(Cell goal) const {
  if (!grid_.is_free(goal))
    throw std::out_of_range("distance table: goal " + grid_.describe(goal) + " is not a free cell");
  const uint64_t now = ++clock_;
  {
    std::shared_lock lock(mutex_);
    auto it = rows_.find(goal);
    if (it != rows_.end()) {
      it->second->last_use.store(now, std::memory_order_relaxed);
      return it->second->row;
    }
  }
  // BFS outside the lock: two threads may race to compute the same row; one copy wins.
  auto fresh = std::make_shared<const DistRow>(grid_, goal, blocked_.empty() ? nullptr : &blocked_);
  ++bfs_count_;
  std::unique_lock lock(mutex_);
  auto [it, inserted] = rows_.try_emplace(goal);
  if (inserted) {
    it->second = std::make_unique<Entry>();
    it->second->row = fresh;
    bytes_ += fresh->bytes();
  }
  it->second->last_use.store(now, std::memory_order_relaxed);
  auto result = it->second->row;
  if (bytes_ > budget_) evict_locked();
  return result;
}

void DistTable::evict_locked() const {
  // Drop the least recently used half of the budget's worth of rows in one pass, so the
  // O(n log n) sort is amortised over many insertions.
  std::vector<std::pair<uint64_t, Cell>> order;
  order.reserve(rows_.size());
  for (auto& [goal, e] : rows_) order.emplace_back(e->last_use.load(), goal);
  std::sort(order.begin(), order.end());
  const size_t target = budget_ / 2;
  for (auto& [use, goal] : order) {
    if (bytes_ <= target || rows_.size() <= 1) break;
    auto it = rows_.find(goal);
    bytes_ -= it->second->row->bytes();
    rows_.erase(it);
  }
}

size_t DistTable::cached_rows() const {
  std::shared_lock lock(mutex_);
  return rows_.size();
}

size_t DistTable::cached_bytes() const {
  std::shared_lock lock(mutex_);
  return bytes_;
}

}  // namespace gdrhcr
