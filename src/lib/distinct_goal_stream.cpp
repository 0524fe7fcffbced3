#include "gdrhcr/distinct_goal_stream.hpp"

namespace gdrhcr {

namespace {
// Redraws per goal before giving up and handing out a held goal (only when nearly every cell of
// the agent's component is some other agent's goal).
constexpr int kMaxRedraws = 10000;
}  // namespace

DistinctGoalStream::DistinctGoalStream(std::unique_ptr<TaskStream> inner) : inner_(std::move(inner)) {}

bool DistinctGoalStream::held_by_other(int agent, Cell c) const {
  auto it = held_.find(c);
  const int mine = last_[agent] == c ? 1 : 0;
  return it != held_.end() && it->second - mine > 0;
}

Cell DistinctGoalStream::next_goal(int agent, Cell current) {
  if (static_cast<int>(last_.size()) <= agent) last_.resize(agent + 1, kNoCell);
  Cell g = inner_->next_goal(agent, current);
  for (int k = 0; k < kMaxRedraws && held_by_other(agent, g); ++k, ++redraws_) g = inner_->next_goal(agent, current);
  if (last_[agent] != kNoCell && --held_[last_[agent]] == 0) held_.erase(last_[agent]);
  last_[agent] = g;
  ++held_[g];
  return g;
}

std::unique_ptr<TaskStream> DistinctGoalStream::clone_fresh() const {
  return std::make_unique<DistinctGoalStream>(inner_->clone_fresh());
}

}  // namespace gdrhcr
