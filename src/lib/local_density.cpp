#include "gdrhcr/local_density.hpp"

#include <algorithm>
#include <cstdint>

namespace gdrhcr {

void LocalDensity::count(const std::vector<Cell>& positions) {
  const int w = grid_.width(), h = grid_.height();
  std::vector<uint8_t> has_agent(grid_.num_cells(), 0);
  for (Cell c : positions) has_agent[c] = 1;
  free_sum_.assign(static_cast<size_t>(w + 1) * (h + 1), 0);
  agent_sum_.assign(free_sum_.size(), 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t k = static_cast<size_t>(y + 1) * (w + 1) + (x + 1);
      const Cell c = grid_.cell(x, y);
      free_sum_[k] = grid_.is_free(c) + free_sum_[k - 1] + free_sum_[k - (w + 1)] - free_sum_[k - (w + 1) - 1];
      agent_sum_[k] = has_agent[c] + agent_sum_[k - 1] + agent_sum_[k - (w + 1)] - agent_sum_[k - (w + 1) - 1];
    }
}

double LocalDensity::around(const std::array<int, 4>& box, int margin) const {
  const int w = grid_.width();
  const int x0 = std::max(0, box[0] - margin), y0 = std::max(0, box[1] - margin);
  const int x1 = std::min(grid_.width() - 1, box[2] + margin), y1 = std::min(grid_.height() - 1, box[3] + margin);
  auto sum = [&](const std::vector<int>& s) {
    auto at = [&](int x, int y) { return s[static_cast<size_t>(y) * (w + 1) + x]; };
    return at(x1 + 1, y1 + 1) - at(x0, y1 + 1) - at(x1 + 1, y0) + at(x0, y0);
  };
  const int free = sum(free_sum_);
  return free > 0 ? double(sum(agent_sum_)) / free : 1.0;
}

}  // namespace gdrhcr
