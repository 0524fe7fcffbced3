// Local guidance: short spatio-temporal paths planned with collision costs, which PIBT follows.
// Idea after Arita & Okumura, "Lifelong LaCAM with Local Guidance" (SoCS 2026): every agent
// gets a path over the next W timesteps from a space-time A* whose cost is time plus a penalty
// for every step that runs into another agent's guidance path (a vertex or a swap), and whose
// heuristic is the shortest-path distance to the goal. PIBT then tries each agent's next
// guidance cell first, so agents spread over parallel aisles and queue instead of meeting
// head-on, while PIBT keeps the step collision-free.
//
// A search ends at the window's end or on the goal (the agent gets its next goal there).
// Guidance paths are kept across steps in absolute time and replanned lazily: when the agent is
// not where its path says, when its goal changed, or when less than half the window is left.
// The collision table counts, per (time mod (W+1), cell), the guidance paths there and, per
// direction, those leaving the cell, so adding, removing and querying a path is O(W).
#pragma once

#include <chrono>
#include <cstdint>
#include <random>
#include <vector>

#include "gdrhcr/planner.hpp"

namespace gdrhcr {

struct LocalGuidanceConfig {
  int window = 20;               // W: timesteps each guidance path covers
  double collision_cost = 3.0;   // added per step that meets another path (vertex or swap)
  // false: replan every agent every step unless its kept path is provably as good (it meets
  // nobody and gains a step on the goal every step); true: keep paths until they are left,
  // the goal changes, they meet another path or less than `keep` steps are left (cheaper).
  bool lazy = false;
  // With lazy = false: keep provably optimal paths instead of replanning them (see the .cpp):
  // about half the CPU time, ~1% lower throughput on empty-48-48 (re-drawn ties spread traffic).
  bool keep_optimal = false;
  int max_expansions = 4000;    // per search; past it the deepest cheapest node so far is used
  int keep = -1;                 // a kept path must still cover this many steps (-1: window / 2)
  uint64_t seed = 1;             // random order of neighbours in the search
  int recheck = 20;              // a kept path is replanned if it meets another path within this many steps
};

class LocalGuidance {
 public:
  LocalGuidance(const Grid& grid, int num_agents, LocalGuidanceConfig config);

  // Brings the guidance of `agents` up to date for timestep world.timestep, in the given order
  // (earlier agents' paths are seen by later ones). Paths of other agents stay in the table.
  // With a deadline, agents not reached by then keep no guidance this step (counted).
  void update(const WorldView& world, const std::vector<int>& agents,
              std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max());
  // Sets agent i's expected path from time world.timestep on (e.g. a plan made by another
  // solver), so guidance searches avoid it; path[0] is its cell now.
  void set_path(int i, int now, const std::vector<Cell>& path);
  // Forgets agent i's path.
  void clear(int i);

  // Agent i's next guidance cell, or kNoCell when it has none for this step.
  Cell next_cell(int i, int now, Cell at) const;
  // Agent i's guidance path from `now` on (empty when none).
  std::vector<Cell> path_from(int i, int now) const;

  long searches() const { return searches_; }
  long cut_short() const { return cut_short_; }
  long kept() const { return kept_; }
  long expansions() const { return expansions_; }
  const LocalGuidanceConfig& config() const { return cfg_; }

 private:
  struct Node {
    float g, f;
    int32_t t;
    Cell v;
    int32_t parent;
  };
  void drop_past(int i, int now);
  void enroll(int i, int sign);
  bool is_valid(const WorldView& world, int i) const;
  bool still_optimal(const WorldView& world, int i);
  void plan(const WorldView& world, int i);
  int collisions(Cell from, Cell to, int abs_t) const;  // others' conflicts with from -> to at abs_t
  int slot(int abs_t) const { return abs_t % slots_; }
  int dir(Cell from, Cell to) const;

  const Grid& grid_;
  LocalGuidanceConfig cfg_;
  int slots_;
  std::vector<std::vector<Cell>> path_;  // per agent: cells at start_[i], start_[i]+1, ...
  std::vector<int> start_;
  std::vector<Cell> goal_;               // the goal each path was planned for
  std::vector<uint16_t> at_;             // [slot * cells + c]: paths at c
  std::vector<uint16_t> leaving_;        // [(slot * cells + c) * 4 + dir]: paths leaving c by dir
  // Search scratch: closed marks stamped per (t, cell), node pool, open list.
  std::vector<uint32_t> closed_, seen_;
  std::vector<float> best_g_;
  std::minstd_rand rng_;
  uint32_t stamp_ = 0;
  std::vector<Node> nodes_;
  struct OpenEntry {  // what the heap compares, kept inline for locality
    float f;
    int32_t t, id;
  };
  std::vector<OpenEntry> open_;
  long searches_ = 0, expansions_ = 0, cut_short_ = 0, kept_ = 0;
};

}  // namespace gdrhcr
