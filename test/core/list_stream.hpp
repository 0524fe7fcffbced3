// Test fixture: a task stream with fixed per-agent goal lists, cycled.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "gdrhcr/task_stream.hpp"

namespace gdrhcr::test_support {

class ListStream : public TaskStream {
 public:
  explicit ListStream(std::vector<std::vector<Cell>> goals) : goals_(std::move(goals)), next_(goals_.size(), 0) {}
  std::string name() const override { return "list"; }
  Cell next_goal(int agent, Cell) override {
    auto& g = goals_[agent];
    return g[next_[agent]++ % g.size()];
  }
  std::unique_ptr<TaskStream> clone_fresh() const override { return std::make_unique<ListStream>(goals_); }

 private:
  std::vector<std::vector<Cell>> goals_;
  std::vector<size_t> next_;
};

}  // namespace gdrhcr::test_support
