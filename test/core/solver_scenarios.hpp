// Test fixtures shared by the solver tests (local guidance, motion forecast): a simulation that
// records paths, and the corridor with a dead-end pocket (a map that is not biconnected) every
// product solver must get through with goals reached.
#pragma once

#include <memory>
#include <vector>

#include "list_stream.hpp"

#include "gdrhcr/grid.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/task_stream.hpp"

namespace gdrhcr::test_support {

// A run of `steps` steps; the simulator validates every executed step and records the paths.
inline SimResult run(const Grid& g, TaskStream& tasks, Planner& p, const std::vector<Cell>& starts, int steps) {
  DistTable dist(g);
  SimOptions opt;
  opt.steps = steps;
  opt.record_paths = true;
  return run_simulation(g, dist, tasks, p, starts, opt);
}

// A one-lane corridor with a two-cell pocket below its middle: two agents shuttle between the
// corridor's ends (head on), a third starts in the pocket and shuttles between its bottom and
// the corridor. 100 steps. make(grid, agents) builds the planner (a std::unique_ptr<Planner>).
template <class MakePlanner>
SimResult run_corridor_with_pocket(MakePlanner make) {
  const Grid g = Grid::from_rows({"..........", "@@@@.@@@@@", "@@@@.@@@@@"});
  auto planner = make(g, 3);
  ListStream tasks({{g.cell(9, 0), g.cell(0, 0)}, {g.cell(0, 0), g.cell(9, 0)}, {g.cell(4, 2), g.cell(5, 0)}});
  return run(g, tasks, *planner, {g.cell(0, 0), g.cell(9, 0), g.cell(4, 1)}, 100);
}

}  // namespace gdrhcr::test_support
