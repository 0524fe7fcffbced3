#include "gdrhcr/validator.hpp"

#include <sstream>

namespace gdrhcr {

std::string StepViolation::describe(const Grid& grid, int timestep) const {
  std::ostringstream os;
  os << "step " << timestep << " -> " << timestep + 1 << ": ";
  switch (kind) {
    case Kind::Vertex:
      os << "vertex collision: agents " << agent_a << " and " << agent_b << " both at "
         << grid.describe(to);
      break;
    case Kind::Edge:
      os << "edge collision: agents " << agent_a << " and " << agent_b << " swap "
         << grid.describe(from) << " and " << grid.describe(to);
      break;
    case Kind::Obstacle:
      os << "agent " << agent_a << " moves from " << grid.describe(from)
         << " into an obstacle or off the map at " << grid.describe(to);
      break;
    case Kind::Jump:
      os << "agent " << agent_a << " jumps from " << grid.describe(from) << " to "
         << grid.describe(to) << " (not adjacent)";
      break;
    case Kind::AgentCount:
      os << "the plan covers a different number of agents than the fleet";
      break;
    case Kind::Action:
      os << "agent " << agent_a << " goes from " << grid.describe(from) << " facing " << heading_name(from_heading)
         << " to " << grid.describe(to) << " facing " << heading_name(to_heading)
         << ", which is not one action of the rotation model (F forward into the faced cell, R, C, W)";
      break;
    case Kind::Heading:
      os << "the rotation model needs every agent's heading (0..3) before and after the step";
      if (agent_a >= 0) os << "; agent " << agent_a << " has none";
      break;
  }
  return os.str();
}

StepValidator::StepValidator(const Grid& grid, ActionModel model)
    : grid_(grid),
      model_(model),
      occupant_now_(grid.num_cells(), -1),
      occupant_next_(grid.num_cells(), -1),
      stamp_now_(grid.num_cells(), 0),
      stamp_next_(grid.num_cells(), 0) {}

// Rotation: every agent's (cell, heading) changes by one action. Runs after the cell checks, so
// cells are free and adjacent here.
std::optional<StepViolation> StepValidator::check_actions(const std::vector<Cell>& prev,
                                                          const std::vector<Cell>& next,
                                                          const std::vector<Heading>* prev_headings,
                                                          const std::vector<Heading>* next_headings) const {
  using K = StepViolation::Kind;
  if (!prev_headings || !next_headings || prev_headings->size() != prev.size() ||
      next_headings->size() != prev.size())
    return StepViolation{K::Heading};
  for (size_t i = 0; i < prev.size(); ++i) {
    const Heading a = (*prev_headings)[i], b = (*next_headings)[i];
    if (a < 0 || a > 3 || b < 0 || b > 3) return StepViolation{K::Heading, int(i)};
    if (!action_between(grid_, {prev[i], a}, {next[i], b}))
      return StepViolation{K::Action, int(i), -1, prev[i], next[i], a, b};
  }
  return std::nullopt;
}

std::optional<StepViolation> StepValidator::check(const std::vector<Cell>& prev, const std::vector<Cell>& next,
                                                  const std::vector<Heading>* prev_headings,
                                                  const std::vector<Heading>* next_headings) {
  using K = StepViolation::Kind;
  if (prev.size() != next.size()) return StepViolation{K::AgentCount};
  ++stamp_;
  const int n = static_cast<int>(prev.size());
  for (int i = 0; i < n; ++i) {
    if (!grid_.is_free(next[i])) return StepViolation{K::Obstacle, i, -1, prev[i], next[i]};
    if (!grid_.step_allowed(prev[i], next[i])) return StepViolation{K::Jump, i, -1, prev[i], next[i]};
    if (stamp_next_[next[i]] == stamp_)
      return StepViolation{K::Vertex, occupant_next_[next[i]], i, prev[i], next[i]};
    stamp_next_[next[i]] = stamp_;
    occupant_next_[next[i]] = i;
    stamp_now_[prev[i]] = stamp_;
    occupant_now_[prev[i]] = i;
  }
  for (int i = 0; i < n; ++i) {
    if (next[i] == prev[i] || stamp_now_[next[i]] != stamp_) continue;
    const int j = occupant_now_[next[i]];
    if (j != i && next[j] == prev[i]) return StepViolation{K::Edge, i, j, prev[i], next[i]};
  }
  if (model_ == ActionModel::kRotation) return check_actions(prev, next, prev_headings, next_headings);
  return std::nullopt;
}

void StepValidator::require_valid(const std::vector<Cell>& prev, const std::vector<Cell>& next, int timestep,
                                  const std::vector<Heading>* prev_headings,
                                  const std::vector<Heading>* next_headings) {
  if (auto v = check(prev, next, prev_headings, next_headings)) throw CollisionError(v->describe(grid_, timestep));
}

}  // namespace gdrhcr
