#include "gdrhcr/local_guidance.hpp"

#include <algorithm>
#include <cmath>

namespace gdrhcr {


LocalGuidance::LocalGuidance(const Grid& grid, int num_agents, LocalGuidanceConfig config)
    : grid_(grid),
      cfg_(config),
      slots_(config.window + 1),
      path_(num_agents),
      start_(num_agents, 0),
      goal_(num_agents, kNoCell),
      at_(static_cast<size_t>(slots_) * grid.num_cells(), 0),
      leaving_(static_cast<size_t>(slots_) * grid.num_cells() * 4, 0),
      closed_(static_cast<size_t>(slots_) * grid.num_cells(), 0),
      seen_(static_cast<size_t>(slots_) * grid.num_cells(), 0),
      best_g_(static_cast<size_t>(slots_) * grid.num_cells(), 0.f),
      rng_(config.seed) {
  if (cfg_.window < 1) throw ParamError("local guidance: window must be >= 1");
  if (!(cfg_.collision_cost >= 0)) throw ParamError("local guidance: collision cost must be >= 0");
}

int LocalGuidance::dir(Cell from, Cell to) const {
  const int d = to - from;
  if (d == 1) return 0;
  if (d == -1) return 1;
  return d > 0 ? 2 : 3;
}

void LocalGuidance::enroll(int i, int sign) {
  const auto& p = path_[i];
  const size_t cells = grid_.num_cells();
  for (size_t k = 0; k < p.size(); ++k) {
    const int s = slot(start_[i] + static_cast<int>(k));
    at_[s * cells + p[k]] += sign;
    if (k + 1 < p.size() && p[k + 1] != p[k]) leaving_[(s * cells + p[k]) * 4 + dir(p[k], p[k + 1])] += sign;
  }
}

void LocalGuidance::clear(int i) {
  enroll(i, -1);
  path_[i].clear();
  goal_[i] = kNoCell;
}

// Removes the part of agent i's path before `now` from the table (its slots are reused).
void LocalGuidance::drop_past(int i, int now) {
  auto& p = path_[i];
  if (p.empty()) return;
  const int k = now - start_[i];
  if (k <= 0) {
    if (k < 0) clear(i);  // time went backwards (a new run): forget
    return;
  }
  if (k >= static_cast<int>(p.size())) {
    clear(i);
    return;
  }
  const size_t cells = grid_.num_cells();
  for (int s = 0; s < k; ++s) {
    const int sl = slot(start_[i] + s);
    at_[sl * cells + p[s]] -= 1;
    if (p[s + 1] != p[s]) leaving_[(sl * cells + p[s]) * 4 + dir(p[s], p[s + 1])] -= 1;
  }
  p.erase(p.begin(), p.begin() + k);
  start_[i] = now;
}

void LocalGuidance::set_path(int i, int now, const std::vector<Cell>& path) {
  enroll(i, -1);
  const size_t len = std::min<size_t>(path.size(), slots_);
  path_[i].assign(path.begin(), path.begin() + len);
  start_[i] = now;
  goal_[i] = kNoCell;  // not a guidance path: replanned whenever guidance is asked for
  enroll(i, +1);
}

int LocalGuidance::collisions(Cell from, Cell to, int abs_t) const {
  const size_t cells = grid_.num_cells();
  int c = at_[slot(abs_t + 1) * cells + to];
  if (from != to) c += leaving_[(slot(abs_t) * cells + to) * 4 + dir(to, from)];
  return c;
}

bool LocalGuidance::is_valid(const WorldView& world, int i) const {
  const auto& p = path_[i];
  if (p.size() < 2 || start_[i] != world.timestep || p[0] != world.positions[i]) return false;
  const Cell goal = world.goals[i].empty() ? world.positions[i] : world.goals[i][0];
  if (goal_[i] != goal) return false;
  if (!cfg_.lazy) return false;
  // Keep at least `keep` steps ahead (default half the window), unless the path ends on the goal.
  const int keep = cfg_.keep >= 0 ? cfg_.keep : cfg_.window / 2;
  if (static_cast<int>(p.size()) <= keep + 1 && p.back() != goal) return false;
  // Replan a path that now meets another one (its own entries count once at each vertex).
  const size_t cells = grid_.num_cells();
  const int horizon = std::min<int>(p.size(), cfg_.recheck + 1);
  for (int k = 1; k < horizon; ++k) {
    if (at_[slot(start_[i] + k) * cells + p[k]] > 1) return false;
    if (p[k] != p[k - 1] && leaving_[(slot(start_[i] + k - 1) * cells + p[k]) * 4 + dir(p[k], p[k - 1])] > 0)
      return false;
  }
  return true;
}

// Replanning every step (lazy = false) would return an equally cheap path for an agent whose
// kept path meets nobody and approaches the goal by one every step: no path can do better. Such
// a path is kept and, if it stops short of the goal, extended by conflict-free steps towards the
// goal up to the window; otherwise (or if no such step exists) the agent is replanned.
bool LocalGuidance::still_optimal(const WorldView& world, int i) {
  auto& p = path_[i];
  if (p.size() < 2 || start_[i] != world.timestep || p[0] != world.positions[i]) return false;
  const Cell goal = world.goals[i].empty() ? world.positions[i] : world.goals[i][0];
  if (goal_[i] != goal) return false;
  const size_t cells = grid_.num_cells();
  const auto row_ptr = world.dist.row(goal);
  const DistRow& row = *row_ptr;
  const int h0 = row[p[0]];
  for (size_t k = 1; k < p.size(); ++k) {
    if (row[p[k]] != h0 - static_cast<int>(k)) return false;
    if (at_[slot(start_[i] + k) * cells + p[k]] > 1) return false;
    if (leaving_[(slot(start_[i] + k - 1) * cells + p[k]) * 4 + dir(p[k], p[k - 1])] > 0) return false;
  }
  while (p.back() != goal && static_cast<int>(p.size()) < cfg_.window + 1) {
    const Cell last = p.back();
    const int t_last = start_[i] + static_cast<int>(p.size()) - 1;
    Cell options[4];
    int m = 0;
    for (Cell u : grid_.neighbours(last))
      if (row[u] == row[last] - 1 && at_[slot(t_last + 1) * cells + u] == 0 &&
          leaving_[(slot(t_last) * cells + u) * 4 + dir(u, last)] == 0)
        options[m++] = u;
    if (m == 0) return false;
    const Cell u = options[m == 1 ? 0 : rng_() % m];
    p.push_back(u);
    at_[slot(t_last + 1) * cells + u] += 1;
    leaving_[(slot(t_last) * cells + last) * 4 + dir(last, u)] += 1;
  }
  return true;
}

void LocalGuidance::update(const WorldView& world, const std::vector<int>& agents,
                           std::chrono::steady_clock::time_point deadline) {
  const int now = world.timestep;
  const bool timed = deadline != std::chrono::steady_clock::time_point::max();
  for (size_t i = 0; i < path_.size(); ++i) drop_past(static_cast<int>(i), now);
  for (size_t k = 0; k < agents.size(); ++k) {
    const int i = agents[k];
    if (cfg_.lazy ? is_valid(world, i) : (cfg_.keep_optimal && still_optimal(world, i))) {
      ++kept_;
      continue;
    }
    enroll(i, -1);
    path_[i].clear();
    if (timed && (k % 16) == 0 && std::chrono::steady_clock::now() >= deadline) {
      ++cut_short_;  // out of time: no guidance for the rest; PIBT uses distances for them
      for (size_t r = k + 1; r < agents.size(); ++r) {
        if (is_valid(world, agents[r])) continue;
        enroll(agents[r], -1);
        path_[agents[r]].clear();
      }
      return;
    }
    plan(world, i);
    enroll(i, +1);
  }
}

// Space-time A* over (t, cell), t = 0..W: cost 1 per step plus collision_cost (and a tiny
// per-conflict count) when a step meets another path; heuristic the distance to the goal.
// Among equal f the deeper node goes first, so free paths are found almost without branching.
void LocalGuidance::plan(const WorldView& world, int i) {
  ++searches_;
  const Cell at = world.positions[i];
  const Cell goal = world.goals[i].empty() ? at : world.goals[i][0];
  goal_[i] = goal;
  start_[i] = world.timestep;
  auto& out = path_[i];
  const int W = cfg_.window;
  if (at == goal) {  // rest on the goal
    out.assign(W + 1, at);
    return;
  }
  const auto row_ptr = world.dist.row(goal);
  const DistRow& row = *row_ptr;
  const size_t cells = grid_.num_cells();
  if (++stamp_ == 0) {
    std::fill(closed_.begin(), closed_.end(), 0);
    std::fill(seen_.begin(), seen_.end(), 0);
    stamp_ = 1;
  }
  nodes_.clear();
  open_.clear();
  auto worse = [](const OpenEntry& x, const OpenEntry& y) {
    if (x.f != y.f) return x.f > y.f;
    return x.t < y.t;  // deeper first
  };
  nodes_.push_back({0.f, static_cast<float>(row[at]), 0, at, -1});
  open_.push_back({nodes_[0].f, 0, 0});
  int32_t best = 0;
  int expanded = 0;
  while (!open_.empty()) {
    std::pop_heap(open_.begin(), open_.end(), worse);
    const int32_t id = open_.back().id;
    open_.pop_back();
    const Node n = nodes_[id];
    uint32_t& mark = closed_[static_cast<size_t>(n.t) * cells + n.v];
    if (mark == stamp_) continue;
    mark = stamp_;
    // Done on the goal (the agent gets its next goal there): that path, even when a deeper node
    // was popped before it. Such a node is no cheaper and does not reach the goal; following
    // it (waiting beside a goal another agent rests on, where stepping in costs a collision at
    // every time) kept an agent off that goal for ever. PIBT pushes the resting agent away.
    if (n.v == goal) {
      best = id;
      break;
    }
    if (n.t > nodes_[best].t || (n.t == nodes_[best].t && n.f < nodes_[best].f)) best = id;
    // Done at the window's end (or out of expansions: the deepest cheapest node so far).
    if (n.t == W || ++expanded > cfg_.max_expansions) break;
    auto expand = [&](Cell u) {
      const size_t key = static_cast<size_t>(n.t + 1) * cells + u;
      if (closed_[key] == stamp_) return;
      const int h = row[u];
      if (h >= kUnreachable) return;
      const int c = collisions(n.v, u, world.timestep + n.t);
      float g = n.g + 1.f;
      if (c > 0) g += static_cast<float>(cfg_.collision_cost) + 1e-3f * c;
      if (seen_[key] == stamp_ && best_g_[key] <= g) return;  // reached as cheaply before
      seen_[key] = stamp_;
      best_g_[key] = g;
      nodes_.push_back({g, g + h, n.t + 1, u, id});
      open_.push_back({g + h, n.t + 1, static_cast<int32_t>(nodes_.size() - 1)});
      std::push_heap(open_.begin(), open_.end(), worse);
    };
    // Neighbours in a random order, so equally good paths do not all bend the same way.
    Cell nb[4];
    int m = 0;
    for (Cell u : grid_.neighbours(n.v)) nb[m++] = u;
    for (int a = m - 1; a > 0; --a) std::swap(nb[a], nb[rng_() % (a + 1)]);
    for (int a = 0; a < m; ++a) expand(nb[a]);
    expand(n.v);
  }
  expansions_ += expanded;
  out.assign(nodes_[best].t + 1, kNoCell);
  for (int32_t k = best; k >= 0; k = nodes_[k].parent) out[nodes_[k].t] = nodes_[k].v;
}

Cell LocalGuidance::next_cell(int i, int now, Cell at) const {
  const auto& p = path_[i];
  if (p.size() < 2 || start_[i] != now || p[0] != at) return kNoCell;
  return p[1];
}

std::vector<Cell> LocalGuidance::path_from(int i, int now) const {
  const auto& p = path_[i];
  const int k = now - start_[i];
  if (p.empty() || k < 0 || k >= static_cast<int>(p.size())) return {};
  return std::vector<Cell>(p.begin() + k, p.end());
}

}  // namespace gdrhcr
