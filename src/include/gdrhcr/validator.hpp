// Checks every executed step of a simulation: a vertex collision (two agents in one cell), an
// edge collision (two agents swapping cells), a move into an obstacle or off the map, and a
// jump to a non-adjacent cell are all violations. In the rotation action model (action_model.hpp)
// each agent's (cell, heading) must also change by exactly one action, F, R, C or W: forward only
// into the free cell its heading faces, a quarter turn in place, or a wait. A violation is a bug
// in a planner, so the simulator treats it as a hard error, never as a statistic.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/grid.hpp"

namespace gdrhcr {

struct StepViolation {
  // Action: not one action of the rotation model; Heading: headings missing or not 0..3.
  enum class Kind { Vertex, Edge, Obstacle, Jump, AgentCount, Action, Heading };
  Kind kind;
  int agent_a = -1;
  int agent_b = -1;  // the other agent for Vertex and Edge
  Cell from = kNoCell, to = kNoCell;
  gdrhcr::Heading from_heading = kNoHeading, to_heading = kNoHeading;  // Action
  std::string describe(const Grid& grid, int timestep) const;
};

class CollisionError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Reuses per-cell scratch buffers across steps, so a check costs O(agents), not O(cells).
class StepValidator {
 public:
  explicit StepValidator(const Grid& grid, ActionModel model = ActionModel::kMapf);
  // The first violation in the move prev -> next, if any. The rotation model needs the headings
  // before and after (one per agent); the mapf model ignores them.
  std::optional<StepViolation> check(const std::vector<Cell>& prev, const std::vector<Cell>& next,
                                     const std::vector<Heading>* prev_headings = nullptr,
                                     const std::vector<Heading>* next_headings = nullptr);
  // Throws CollisionError with a description naming agents, cells and the timestep.
  void require_valid(const std::vector<Cell>& prev, const std::vector<Cell>& next, int timestep,
                     const std::vector<Heading>* prev_headings = nullptr,
                     const std::vector<Heading>* next_headings = nullptr);
  ActionModel action_model() const { return model_; }

 private:
  std::optional<StepViolation> check_actions(const std::vector<Cell>& prev, const std::vector<Cell>& next,
                                             const std::vector<Heading>* prev_headings,
                                             const std::vector<Heading>* next_headings) const;
  const Grid& grid_;
  ActionModel model_;
  std::vector<int> occupant_now_, occupant_next_;  // agent id per cell, valid when stamp matches
  std::vector<unsigned> stamp_now_, stamp_next_;
  unsigned stamp_ = 0;
};

}  // namespace gdrhcr
