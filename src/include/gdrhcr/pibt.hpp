// PIBT: Priority Inheritance with Backtracking for lifelong MAPF.
// Okumura, Machida, Défago, Tamura, "Priority Inheritance with Backtracking for Iterative
// Multi-agent Path Finding", Artificial Intelligence 310, 2022 (IJCAI 2019).
//
// One timestep at a time: agents decide in priority order; an agent that wants a cell held by an
// undecided agent lends it its priority, and that agent must move away or the request
// backtracks. Priorities rise with the time since an agent last reached its goal, so nobody
// starves. Never produces a vertex or edge collision.
#pragma once

#include <random>
#include <vector>

#include "gdrhcr/planner.hpp"

namespace gdrhcr {

// The step function, reusable on a subset of agents (GD-RHCR moves large groups with it).
class PibtStep {
 public:
  PibtStep(const Grid& grid, int num_agents, uint64_t seed);

  // Decides next[i] for every agent in `agents` (all agents when empty). `fixed_moves` holds the
  // (from, to) cells of agents outside `agents` whose moves are already decided; PIBT keeps its
  // agents out of both cells. The caller must not fix a move into a cell where one of `agents`
  // stands (PIBT may need to keep that agent in place). Priorities: an agent on its goal drops
  // to its tie-breaker, the others' rise by one.
  void step(const WorldView& world, std::vector<Cell>& next,
            const std::vector<int>& agents = {},
            const std::vector<std::pair<Cell, Cell>>& fixed_moves = {});

 private:
  bool push(const WorldView& world, int ai, int aj, std::vector<Cell>& next);

  const Grid& grid_;
  std::mt19937_64 rng_;
  std::vector<double> priority_;           // elapsed steps + a per-agent tie-breaker in [0,1)
  std::vector<int> occupied_now_, occupied_next_;  // agent per cell; -1 free, -2 held by a fixed move
  std::vector<std::shared_ptr<const DistRow>> rows_;  // each agent's goal row, this step
  std::vector<int> order_;
  std::vector<Cell> candidates_scratch_;
};

class PibtPlanner : public Planner {
 public:
  PibtPlanner(const Grid& grid, int num_agents, uint64_t seed);
  std::string name() const override { return "pibt"; }
  StepReport plan_step(const WorldView& world, std::vector<Cell>& next) override;
  nlohmann::json params() const override { return {{"seed", seed_}}; }

 private:
  uint64_t seed_;
  PibtStep pibt_;
};

}  // namespace gdrhcr
