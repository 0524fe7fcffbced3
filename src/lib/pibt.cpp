#include "gdrhcr/pibt.hpp"

#include <algorithm>
#include <chrono>
#include <numeric>

#include "gdrhcr/task_stream.hpp"

namespace gdrhcr {

namespace {
constexpr int kFree = -1;
constexpr int kFixed = -2;  // a cell held by an agent PIBT does not move this call
}  // namespace

PibtStep::PibtStep(const Grid& grid, int num_agents, uint64_t seed)
    : grid_(grid),
      rng_(mix_seed(seed, 0x50494254ULL)),
      priority_(num_agents),
      occupied_now_(grid.num_cells(), kFree),
      occupied_next_(grid.num_cells(), kFree),
      rows_(num_agents) {
  std::uniform_real_distribution<double> tie(0.0, 1.0);
  for (auto& p : priority_) p = tie(rng_);
}

void PibtStep::step(const WorldView& world, std::vector<Cell>& next, const std::vector<int>& agents,
                    const std::vector<std::pair<Cell, Cell>>& fixed_moves) {
  const int n = world.num_agents();
  if (static_cast<int>(priority_.size()) < n) {
    std::uniform_real_distribution<double> tie(0.0, 1.0);
    while (static_cast<int>(priority_.size()) < n) priority_.push_back(tie(rng_));
    rows_.resize(n);
  }
  order_.clear();
  if (agents.empty()) {
    order_.resize(n);
    std::iota(order_.begin(), order_.end(), 0);
  } else {
    order_ = agents;
  }
  for (int i : order_) {
    const Cell g = world.goals[i].empty() ? world.positions[i] : world.goals[i][0];
    // Priority: time since the last goal, so long-waiting agents win; the fractional part is a
    // fixed tie-breaker. An agent standing on its goal drops back to the tie-breaker alone.
    if (world.positions[i] == g) priority_[i] -= std::floor(priority_[i]);
    else priority_[i] += 1.0;
    rows_[i] = world.dist.row(g);
    occupied_now_[world.positions[i]] = i;
    next[i] = kNoCell;
  }
  // Immovable agents stay: their cell is taken for t+1, so nobody pushes them or moves in.
  if (world.immovable)
    for (int i : order_)
      if ((*world.immovable)[i]) next[i] = world.positions[i], occupied_next_[world.positions[i]] = i;
  // Agents outside this call keep their moves; their cells at t and t+1 are off limits, which
  // rules out both vertex and swap conflicts with them.
  for (auto& [from, to] : fixed_moves) {
    if (from != kNoCell) occupied_next_[from] = kFixed;
    if (to != kNoCell) occupied_next_[to] = kFixed;
  }
  std::stable_sort(order_.begin(), order_.end(),
                   [&](int a, int b) { return priority_[a] > priority_[b]; });
  for (int i : order_)
    if (next[i] == kNoCell) push(world, i, -1, next);
  // Reset the scratch tables touched this call, so the next call starts clean in O(agents).
  for (int i : order_) {
    occupied_now_[world.positions[i]] = kFree;
    occupied_next_[next[i]] = kFree;
    rows_[i].reset();
  }
  for (auto& [from, to] : fixed_moves) {
    if (from != kNoCell) occupied_next_[from] = kFree;
    if (to != kNoCell) occupied_next_[to] = kFree;
  }
}

bool PibtStep::push(const WorldView& world, int ai, int aj, std::vector<Cell>& next) {
  const Cell here = world.positions[ai];
  const DistRow& row = *rows_[ai];
  // Candidates: the neighbours and staying put, nearest to the goal first; among equals prefer
  // a cell nobody stands on (fewer pushes), then a random order (rng) to break symmetry.
  Cell cand[5];
  int m = 0;
  for (Cell c : grid_.neighbours(here)) cand[m++] = c;
  cand[m++] = here;
  std::shuffle(cand, cand + m, rng_);
  std::stable_sort(cand, cand + m, [&](Cell a, Cell b) {
    if (row[a] != row[b]) return row[a] < row[b];
    return (occupied_now_[a] == kFree) > (occupied_now_[b] == kFree);
  });
  for (int k = 0; k < m; ++k) {
    const Cell u = cand[k];
    if (occupied_next_[u] != kFree) continue;
    if (aj >= 0 && u == world.positions[aj]) continue;  // would swap with the pusher
    const int ak = occupied_now_[u];
    occupied_next_[u] = ai;
    next[ai] = u;
    if (ak >= 0 && ak != ai && next[ak] == kNoCell && !push(world, ak, ai, next)) continue;
    return true;
  }
  occupied_next_[here] = ai;
  next[ai] = here;
  return false;
}

PibtPlanner::PibtPlanner(const Grid& grid, int num_agents, uint64_t seed)
    : seed_(seed), pibt_(grid, num_agents, seed) {}

StepReport PibtPlanner::plan_step(const WorldView& world, std::vector<Cell>& next) {
  const auto t0 = std::chrono::steady_clock::now();
  pibt_.step(world, next);
  return {true, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count()};
}

}  // namespace gdrhcr
