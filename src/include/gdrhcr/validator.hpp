// Checks every executed step of a simulation: a vertex collision (two agents in one cell), an
// edge collision (two agents swapping cells), a move into an obstacle or off the map, and a
// jump to a non-adjacent cell are all violations. A violation is a bug in a planner, so the
// simulator treats it as a hard error, never as a statistic.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "gdrhcr/grid.hpp"

namespace gdrhcr {

struct StepViolation {
  enum class Kind { Vertex, Edge, Obstacle, Jump, AgentCount };
  Kind kind;
  int agent_a = -1;
  int agent_b = -1;  // the other agent for Vertex and Edge
  Cell from = kNoCell, to = kNoCell;
  std::string describe(const Grid& grid, int timestep) const;
};

class CollisionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reuses per-cell scratch buffers across steps, so a check costs O(agents), not O(cells).
class StepValidator {
 public:
  explicit StepValidator(const Grid& grid);
  // The first violation in the move prev -> next, if any.
  std::optional<StepViolation> check(const std::vector<Cell>& prev, const std::vector<Cell>& next);
  // Throws CollisionError with a description naming agents, cells and the timestep.
  void require_valid(const std::vector<Cell>& prev, const std::vector<Cell>& next, int timestep);

 private:
  const Grid& grid_;
  std::vector<int> occupant_now_, occupant_next_;  // agent id per cell, valid when stamp matches
  std::vector<unsigned> stamp_now_, stamp_next_;
  unsigned stamp_ = 0;
};

}  // namespace gdrhcr
