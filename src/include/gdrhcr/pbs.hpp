// PBS: Priority-Based Search.
// Ma, Harabor, Stuckey, Koenig, "Searching with Consistent Prioritization for Multi-Agent Path
// Finding", AAAI 2019; windowed as in RHCR (Li et al., "Lifelong Multi-Agent Path Finding in
// Large-Scale Warehouses", AAAI 2021).
//
// A depth-first search over partial priority orders. Each node holds one path per agent, each
// path avoiding (hard constraints, via SIPP) the paths of all agents above it in the node's
// order. Expanding a node takes its earliest collision inside the window (vertex at t <= H or
// swap departing t < H) between agents a and b and tries both a > b and b > a; in each child the
// lower agent and everyone below it are replanned in topological order, each only if its path
// now collides with a higher one. Agents with no order between them may collide; that is what
// later branches resolve. Success = a node with no collision inside the window.
//
// Backjumping (our addition, on by default): a node is a dead end when neither order of its
// collision (a, b) can be planned. That failure depends only on a, b, their ancestors and the
// paths of those; the decisions below the deepest one that touched that set (added an order
// onto it or replanned one of its agents) leave it as it was, so their siblings would keep
// meeting the same dead end. The search jumps straight back to that decision's sibling instead
// of trying them all, which turns rare multi-second thrashing into quick failures or
// successes. Like PBS itself this is incomplete: a skipped subtree could in principle change
// one of those paths before reaching the collision again.
//
// Limits: a wall-clock time limit and a deterministic node budget (nodes generated, the root
// included), so tests and benchmarks do not depend on machine speed.
//
// Reentrant: no shared mutable state; scratch memory is per thread (thread_local) and reused
// across calls, so GD-RHCR may solve disjoint groups on several threads at once.
#pragma once

#include <vector>

#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/soft_constraint_table.hpp"

namespace gdrhcr {

struct PbsConfig {
  int horizon = 20;           // window H: collisions are resolved for t = 0..H
  double c_soft = 1.0;        // cost per conflict with the soft table (ignored when it is null)
  double time_limit_s = 60.0;
  long node_budget = 0;       // 0 = unlimited
  bool backjump = true;       // skip siblings that cannot undo a dead end (see above)
  // Cells no path may use at any time of the window (immovable agents outside the call).
  const std::vector<Cell>* blocked_cells = nullptr;
  // Rotation model (a rotation DistTable): each start's heading (null: all east). SIPP then plans
  // over (cell, heading) states (sipp.hpp) and the result carries headings. Collisions stay on
  // cells.
  const std::vector<Heading>* start_headings = nullptr;
};

struct PbsResult {
  bool success = false;
  bool timed_out = false;     // cut short by the time limit or the node budget
  std::vector<std::vector<Cell>> paths;  // same order as starts; paths[k][t], size >= horizon+1
  std::vector<std::vector<Heading>> headings;  // rotation: headings[k][t], as paths
  long nodes = 0;             // PBS nodes generated
  long sipp_calls = 0;
  int soft_conflicts = 0;     // of the returned paths with the soft table, inside the window
  double time_s = 0;
};

// goals[k] is agent k's goal sequence (goals[k][0] its current goal, then the known next ones;
// see sipp.hpp for what a path does with them). `soft` may be null. On failure `paths` is empty.
PbsResult solve_pbs(const Grid& grid, const DistTable& dist, const std::vector<Cell>& starts,
                    const std::vector<std::vector<Cell>>& goals, const SoftConstraintTable* soft,
                    const PbsConfig& config);

// The first vertex or swap collision among `paths` inside the window, as (t, a, b) with t = -1
// when there is none. Paths shorter than the window stay at their last cell. For tests and
// callers that want to double-check a plan.
struct PbsCollision {
  int t = -1;
  int a = -1, b = -1;
  bool edge = false;
};
PbsCollision first_collision(const Grid& grid, const std::vector<std::vector<Cell>>& paths, int horizon);

}  // namespace gdrhcr
