// Shortest-path distance tables, one per goal, computed lazily by BFS and cached.
//
// As in Kei18/pibt2 and lacam3 (Okumura et al.), every solver shares one table, so a goal's BFS
// is paid once however many agents and solvers ask. Unlike RHCR's all-pairs table (437 MB on
// warehouse-10-20-10-2-1), only goals in use are kept, under a memory budget: the least
// recently used rows are evicted. Rows are handed out as shared pointers, so eviction never
// invalidates a row a solver is still reading. Thread-safe: parallel groups query it at once.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <unordered_map>
#include <vector>

#include "gdrhcr/grid.hpp"

namespace gdrhcr {

constexpr int kUnreachable = INT32_MAX / 4;

// Distances from every cell to one goal (kUnreachable for obstacles and other components).
class DistRow {
 public:
  // `blocked` (per cell, optional): cells the BFS never enters, though it may start from one.
  DistRow(const Grid& grid, Cell goal, const std::vector<uint8_t>* blocked = nullptr);
  int operator[](Cell c) const { return dist_[c]; }
  Cell goal() const { return goal_; }
  size_t bytes() const { return dist_.size() * sizeof(int32_t); }

 private:
  Cell goal_;
  std::vector<int32_t> dist_;
};

class DistTable {
 public:
  static constexpr size_t kDefaultBudgetBytes = size_t(256) << 20;
  explicit DistTable(const Grid& grid, size_t budget_bytes = kDefaultBudgetBytes);
  // Distances that route around `blocked` free cells, e.g. robots that went offline and now
  // stand where they stopped: paths avoid them, and a goal on one is still accepted (the
  // offline robot's own), but no other cell reaches it.
  DistTable(const Grid& grid, const std::vector<Cell>& blocked, size_t budget_bytes = kDefaultBudgetBytes);

  // The row for `goal`, computing it on first use. Throws std::out_of_range for a blocked goal.
  std::shared_ptr<const DistRow> row(Cell goal) const;
  int get(Cell goal, Cell from) const { return (*row(goal))[from]; }

  const Grid& grid() const { return grid_; }
  size_t cached_rows() const;
  size_t cached_bytes() const;
  uint64_t bfs_count() const { return bfs_count_.load(); }

 private:
  struct Entry {
    std::shared_ptr<const DistRow> row;
    mutable std::atomic<uint64_t> last_use{0};
  };
  void evict_locked() const;

  const Grid& grid_;
  std::vector<uint8_t> blocked_;  // per cell; empty when nothing is blocked
  size_t budget_;
  mutable std::shared_mutex mutex_;
  mutable std::unordered_map<Cell, std::unique_ptr<Entry>> rows_;
  mutable size_t bytes_ = 0;
  mutable std::atomic<uint64_t> clock_{0};
  mutable std::atomic<uint64_t> bfs_count_{0};
};

}  // namespace gdrhcr
