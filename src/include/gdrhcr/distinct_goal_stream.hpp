// Distinct goals: a task stream wrapper that never hands an agent a goal another agent holds.
// It redraws (from the wrapped stream, for the same agent) while the drawn goal equals the goal
// most recently handed to another agent; with the simulator's --lookahead 1 that is every other
// agent's current goal, the rule of LLLG's lifelong runner (Arita & Okumura, "Lifelong LaCAM
// with Local Guidance", SoCS 2026, public code allegorywrite/lllg): a new goal is a free cell
// other than the agent's own and the other agents' current goals. For comparing against its
// figures on the same kind of task stream (docs/results.md, issue 11).
//
// Agents are no longer independent: a draw depends on the other agents' goals at that moment,
// so a fresh clone replayed agent by agent (the free-flow bound) yields an alike stream, not the
// same goals.
#pragma once

#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "gdrhcr/task_stream.hpp"

namespace gdrhcr {

class DistinctGoalStream : public TaskStream {
 public:
  explicit DistinctGoalStream(std::unique_ptr<TaskStream> inner);
  std::string name() const override { return inner_->name() + "+distinct"; }
  Cell next_goal(int agent, Cell current) override;
  std::unique_ptr<TaskStream> clone_fresh() const override;
  long redraws() const { return redraws_; }

 private:
  bool held_by_other(int agent, Cell c) const;
  std::unique_ptr<TaskStream> inner_;
  std::vector<Cell> last_;                // the goal last handed to each agent
  std::unordered_map<Cell, int> held_;    // how many agents' last goal each cell is
  long redraws_ = 0;
};

}  // namespace gdrhcr
