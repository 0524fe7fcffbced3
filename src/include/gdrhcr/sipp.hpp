// SIPP: Safe Interval Path Planning.
// Phillips, Likhachev, "SIPP: Safe Interval Path Planning for Dynamic Environments", ICRA 2011.
// Used as PBS's low level, as in RHCR (Li et al., "Lifelong Multi-Agent Path Finding in
// Large-Scale Warehouses", AAAI 2021), with soft constraints as in GD-RHCR (DeWeese, Li, Qu).
//
// A* over (cell, safe interval, goal index). Per call:
//  - hard constraints (ConstraintTable): cells and moves of higher-priority agents, which a path
//    must never use, for times 0..H (moves departing 0..H-1). Beyond the horizon H nothing is
//    constrained, so a path only has to be collision-free inside the window (RHCR's window).
//  - soft constraints (SoftConstraintTable, optional): each vertex conflict (one other agent in
//    the same cell at the same time, t <= H) and each edge conflict (a swap, departure t < H)
//    adds c_soft to the cost. Safe intervals are split where the soft count changes, so the
//    search is exact: it minimises  arrival time + c_soft * conflicts, ties going to fewer
//    conflicts. c_soft = 0 ignores the table during the search (conflicts are still counted).
//  - goals: a sequence, goals[0] the current goal then the known next goals (WorldView::goals).
//    The agent visits them in order and is done after the last one. The cost is the time at
//    which the agent has visited every goal it can reach and is parked where it may stay.
//
// What the returned path contains (path[t] = cell at t):
//  - it reaches goals[0], and it is at least H+1 long (t = 0..H);
//  - after goals[0] it keeps going to the next known goals (as RHCR does with goal sequences),
//    and after the last one it waits there (or wherever it could park) until t = H;
//  - it is cut at max(H, arrival at goals[0]): past H it only follows a shortest path to
//    goals[0], since nothing is constrained there. Its last cell is free of hard constraints
//    from its arrival on, so the agent may stay there beyond the horizon.
// The heuristic is the shared DistTable (exact past the horizon, which lets the search stop at
// the first node popped at t >= H). Goals unreachable from the start (other components) cut the
// sequence there; with goals[0] unreachable the agent just has to park.
//
// Rotation model (issue 23, action_model.hpp): with a rotation DistTable the search runs over
// (cell, heading, safe interval, goal index). From a node the agent may go forward into the cell
// it faces (departing at any time its interval allows) or make a quarter turn, which keeps it in
// its cell and interval for one step (paying that interval's soft count). The heuristic is the
// rotation row's distance from the node's heading (turns counted). The result carries the heading
// at every t beside the cell (SippResult::headings); a wait keeps the heading.
#pragma once

#include <chrono>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/soft_constraint_table.hpp"

namespace gdrhcr {

// Hard constraints of one low-level call, as per-cell bitmasks over t = 0..H (64 steps a word).
// Reset in O(touched cells), so one table serves many calls.
class ConstraintTable {
 public:
  ConstraintTable(const Grid& grid, int horizon);
  int horizon() const { return horizon_; }
  const Grid& grid() const { return grid_; }

  // A higher-priority agent's path: its cells at t = 0..H (its last cell after it ends) and, for
  // each move p -> q departing t < H, the swap q -> p at t.
  void add_path(const std::vector<Cell>& path);
  void block_vertex(Cell c, int t);           // ignored outside [0, H]
  void block_move(Cell from, Cell to, int t);  // forbids from -> to departing t; ignored outside [0, H)
  bool vertex_blocked(Cell c, int t) const {
    return t >= 0 && t <= horizon_ && (vertex_[size_t(c) * words_ + (t >> 6)] >> (t & 63) & 1);
  }
  bool move_blocked(Cell from, Cell to, int t) const {
    return t >= 0 && t < horizon_ &&
           (move_[(size_t(from) * 4 + dir(from, to)) * words_ + (t >> 6)] >> (t & 63) & 1);
  }
  bool cell_constrained(Cell c) const { return touched_flag_[c] != 0; }
  // True if `path` uses a blocked cell or move inside the window.
  bool violated_by(const std::vector<Cell>& path) const;
  void clear();

 private:
  int dir(Cell from, Cell to) const {
    const int d = to - from;
    return d == 1 ? 0 : d == -1 ? 1 : d > 0 ? 2 : 3;
  }
  void touch(Cell c);

  const Grid& grid_;
  int horizon_, words_;
  std::vector<uint64_t> vertex_;  // cells x words
  std::vector<uint64_t> move_;    // cells x 4 directions x words
  std::vector<uint8_t> touched_flag_;
  std::vector<Cell> touched_;
};

// One agent's query: start and goal sequence with their distance rows, fetched once and reused
// across the many low-level calls PBS makes for the same agent.
struct SippAgent {
  // `heading`: the start heading in the rotation model (ignored, and kNoHeading, in mapf).
  SippAgent(const DistTable& dist, Cell start, const std::vector<Cell>& goals, int horizon,
            Heading heading = kEast);
  Cell start;
  Heading heading = kNoHeading;  // kNoHeading: the mapf model
  std::vector<Cell> goals;  // the reachable prefix of the sequence that can matter before H
  std::vector<std::shared_ptr<const DistRow>> rows;  // rows[k]: distances to goals[k]
  std::vector<int> tail;    // tail[k] = sum of distances goals[k] -> goals[k+1] -> ... -> last
  bool goal0_reachable = true;
};

struct SippLimits {
  long expansion_budget = 0;  // 0 = unlimited; deterministic, unlike the deadline
  std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max();
};

struct SippResult {
  bool found = false;
  bool cut_short = false;       // stopped by the budget or the deadline
  std::vector<Cell> path;
  std::vector<Heading> headings;  // rotation: the heading at every t (same length as path)
  double cost = 0;              // arrival time at the end of the goal sequence + c_soft * conflicts
  int soft_conflicts = 0;       // of the returned path, within the window
  long expansions = 0;
};

// Reusable search state (one per thread): per-cell scratch sized to the grid, reset lazily.
// Bound to one grid: the constraint table passed to `plan` must be built on the same grid.
class Sipp {
 public:
  explicit Sipp(const Grid& grid);
  ~Sipp();
  SippResult plan(const SippAgent& agent, const ConstraintTable& hard,
                  const SoftConstraintTable* soft, double c_soft, const SippLimits& limits = {});
  // Convenience for one-off calls and tests.
  SippResult plan(const DistTable& dist, Cell start, const std::vector<Cell>& goals,
                  const ConstraintTable& hard, const SoftConstraintTable* soft, double c_soft,
                  const SippLimits& limits = {});

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Vertex and edge conflicts of `path` with the table within the window (t <= H, departures < H).
int count_soft_conflicts(const std::vector<Cell>& path, const SoftConstraintTable& soft, int horizon);

}  // namespace gdrhcr
