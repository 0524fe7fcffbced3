#include "gdrhcr/local_guidance.hpp"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include "gdrhcr/task_stream.hpp"
#include "tsan_annotations.hpp"

namespace gdrhcr {

struct LocalGuidance::Parallel {
  tbb::enumerable_thread_specific<Search> search;
};

void LocalGuidance::Counts::add(const Counts& o) {
  searches += o.searches;
  expansions += o.expansions;
  cut_short += o.cut_short;
  kept += o.kept;
  refined += o.refined;
}

LocalGuidance::LocalGuidance(const Grid& grid, int num_agents, LocalGuidanceConfig config)
    : grid_(grid),
      cfg_(config),
      slots_(config.window + 1),
      path_(num_agents),
      start_(num_agents, 0),
      goal_(num_agents, kNoCell),
      occ_(static_cast<size_t>(slots_) * grid.num_cells(), Occupancy{0, {0, 0, 0, 0}}),
      flow_(grid.num_cells(), std::array<uint16_t, 4>{0, 0, 0, 0}),
      contraflow_(static_cast<float>(config.contraflow_cost)),
      rng_(config.seed) {
  if (cfg_.window < 1) throw ParamError("local guidance: window must be >= 1");
  if (!(cfg_.collision_cost >= 0)) throw ParamError("local guidance: collision cost must be >= 0");
  if (cfg_.near_steps < 0) throw ParamError("local guidance: near steps must be >= 0");
  if (!(cfg_.contraflow_cost >= 0)) throw ParamError("local guidance: contraflow cost must be >= 0");
  if (cfg_.phases < 0 || cfg_.phases == 1) throw ParamError("local guidance: phases must be 0 or >= 2");
  if (cfg_.phases >= 2) parallel_ = std::make_unique<Parallel>();
}

LocalGuidance::~LocalGuidance() = default;

int LocalGuidance::band_width() const {
  if (cfg_.phases < 2) return 0;
  return std::max(1, (2 * cfg_.window + cfg_.phases - 2) / (cfg_.phases - 1));
}

void LocalGuidance::enroll(int i, int sign) {
  const auto& p = path_[i];
  for (size_t k = 0; k < p.size(); ++k) {
    const int s = slot(start_[i] + static_cast<int>(k));
    at(p[k], s) += sign;
    if (k + 1 < p.size() && p[k + 1] != p[k]) {
      leaving(p[k], s, dir(p[k], p[k + 1])) += sign;
      flow_[p[k]][dir(p[k], p[k + 1])] += sign;
    }
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
  for (int s = 0; s < k; ++s) {
    const int sl = slot(start_[i] + s);
    at(p[s], sl) -= 1;
    if (p[s + 1] != p[s]) leaving(p[s], sl, dir(p[s], p[s + 1])) -= 1, flow_[p[s]][dir(p[s], p[s + 1])] -= 1;
  }
  p.erase(p.begin(), p.begin() + k);
  start_[i] = now;
}

void LocalGuidance::set_path(int i, int now, const std::vector<Cell>& path, Cell goal) {
  enroll(i, -1);
  const size_t len = std::min<size_t>(path.size(), slots_);
  path_[i].assign(path.begin(), path.begin() + len);
  start_[i] = now;
  goal_[i] = goal;  // kNoCell: not a guidance path, replanned whenever guidance is asked for
  enroll(i, +1);
}

// What a step from -> to in time slot s (into slot s1, the next) pays on top of its 1 for meeting
// other paths: the collision cost (the far one from near_steps ahead on) per kind of conflict met
// (vertex, swap; or once for either), plus a tiny amount per path met, so that among equal costs
// the less crowded step wins, plus the contraflow cost per path planned the other way along the
// edge at any time.
[[gnu::always_inline]] inline float LocalGuidance::collision_penalty(Cell from, Cell to, int s, int s1,
                                                                     int ahead) const {
  const float against = from != to ? contraflow_ * flow_[to][dir(to, from)] : 0.f;
  const int vertex = at(to, s1);
  const int swap = from != to ? leaving(to, s, dir(to, from)) : 0;
  if (vertex + swap == 0) return against;
  const bool far = cfg_.far_collision_cost >= 0 && ahead >= cfg_.near_steps;
  const float cost = static_cast<float>(far ? cfg_.far_collision_cost : cfg_.collision_cost);
  const int kinds = cfg_.cost_per_kind ? (vertex > 0) + (swap > 0) : 1;
  return cost * kinds + 1e-3f * (vertex + swap) + against;
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
  // Replan a path that now meets another one.
  return !meets_another(i, cfg_.recheck + 1);
}

// Whether agent i keeps its path this step (lazy: until it is left or meets another path).
bool LocalGuidance::keeps(const WorldView& world, int i) const { return cfg_.lazy && is_valid(world, i); }

void LocalGuidance::update(const WorldView& world, const std::vector<int>& agents,
                           std::chrono::steady_clock::time_point deadline,
                           std::chrono::steady_clock::time_point refine_until) {
  const int now = world.timestep;
  for (size_t i = 0; i < path_.size(); ++i) drop_past(static_cast<int>(i), now);
  mark_blocked(world, +1);
  // Immovable agents (a robot still making its committed moves, an offline one) are not searched:
  // they stay where they are, as a blocked cell does, and the others' guidance goes around them.
  const std::vector<int>* todo = &agents;
  std::vector<int> movable;
  if (world.immovable) {
    movable.reserve(agents.size());
    for (int i : agents) {
      if (!world.is_immovable(i)) {
        movable.push_back(i);
        continue;
      }
      clear(i);
      path_[i].assign(blocked_steps() + 1, world.positions[i]);
      start_[i] = now;
      enroll(i, +1);
    }
    todo = &movable;
  }
  if (parallel_) {
    update_banded(world, *todo, deadline, refine_until);
  } else {
    update_in_order(world, *todo, deadline, search_, rng_, counts_);
    refine(world, *todo, deadline, refine_until, search_, rng_, counts_);
  }
  mark_blocked(world, -1);
}

// Whether agent i's path meets another path (vertex or swap) within its first `horizon` entries
// (its own entries count once at each vertex).
bool LocalGuidance::meets_another(int i, int horizon) const {
  const auto& p = path_[i];
  const int end = std::min<int>(p.size(), horizon);
  for (int k = 1; k < end; ++k) {
    if (at(p[k], slot(start_[i] + k)) > 1) return true;
    if (p[k] != p[k - 1] && leaving(p[k], slot(start_[i] + k - 1), dir(p[k], p[k - 1])) > 0) return true;
  }
  return false;
}

int LocalGuidance::refine_passes(std::chrono::steady_clock::time_point deadline) const {
  if (cfg_.refine >= 0) return cfg_.refine;
  return deadline != std::chrono::steady_clock::time_point::max() ? LocalGuidanceConfig::kAnytimePasses : 0;
}

// The anytime part: passes over `agents` in order, each searching again every path that meets
// another, with every other path in the table, until a pass finds none, the passes run out or
// the deadline comes.
void LocalGuidance::refine(const WorldView& world, const std::vector<int>& agents,
                           std::chrono::steady_clock::time_point deadline, std::chrono::steady_clock::time_point until,
                           Search& search, std::minstd_rand& rng, Counts& counts) {
  const int passes = refine_passes(deadline);
  until = std::min(until, deadline);
  for (int pass = 0; pass < passes; ++pass) {
    bool any = false;
    for (int i : agents) {
      if (path_[i].empty() || !meets_another(i, slots_)) continue;
      if (std::chrono::steady_clock::now() >= until) return;
      any = true;
      ++counts.refined;
      enroll(i, -1);
      path_[i].clear();
      plan(world, i, search, rng, counts);
      enroll(i, +1);
    }
    if (!any) return;
  }
}

int LocalGuidance::blocked_steps() const {
  return std::min(cfg_.blocked_steps < 0 ? cfg_.window : cfg_.blocked_steps, cfg_.window);
}

// Blocked cells (a late robot still leaving them) count as taken in the searches of this update,
// from now on for `blocked_steps` steps (how long such a cell is expected to stay taken).
void LocalGuidance::mark_blocked(const WorldView& world, int sign) {
  if (!world.blocked) return;
  const int steps = blocked_steps();
  for (Cell c : *world.blocked)
    for (int k = 0; k <= steps; ++k) at(c, slot(world.timestep + k)) += sign;
}

// The sequential update of `agents`, in order (also one band of the parallel update).
void LocalGuidance::update_in_order(const WorldView& world, const std::vector<int>& agents,
                                    std::chrono::steady_clock::time_point deadline, Search& search,
                                    std::minstd_rand& rng, Counts& counts) {
  const bool timed = deadline != std::chrono::steady_clock::time_point::max();
  for (size_t k = 0; k < agents.size(); ++k) {
    const int i = agents[k];
    if (keeps(world, i)) {
      ++counts.kept;
      continue;
    }
    enroll(i, -1);
    path_[i].clear();
    if (timed && std::chrono::steady_clock::now() >= deadline) {  // every search: one can take a ms
      ++counts.cut_short;  // out of time: no guidance for the rest; PIBT uses distances for them
      for (size_t r = k + 1; r < agents.size(); ++r) {
        if (is_valid(world, agents[r])) continue;
        enroll(agents[r], -1);
        path_[agents[r]].clear();
      }
      return;
    }
    plan(world, i, search, rng, counts);
    enroll(i, +1);
  }
}

// The parallel update (see the header): stale paths are dropped first, so every path left
// starts at its agent's cell; then the bands of each phase run concurrently.
void LocalGuidance::update_banded(const WorldView& world, const std::vector<int>& agents,
                                  std::chrono::steady_clock::time_point deadline,
                                  std::chrono::steady_clock::time_point refine_until) {
  const int now = world.timestep;
  for (size_t i = 0; i < path_.size(); ++i)
    if (!path_[i].empty() && (start_[i] != now || path_[i][0] != world.positions[i])) clear(static_cast<int>(i));
  const bool across_x = grid_.width() >= grid_.height();
  const int side = across_x ? grid_.width() : grid_.height();
  const int width = band_width();
  const int bands = (side + width - 1) / width;
  band_agents_.resize(bands);
  for (auto& b : band_agents_) b.clear();
  for (int i : agents) {
    const Cell c = world.positions[i];
    band_agents_[(across_x ? grid_.x_of(c) : grid_.y_of(c)) / width].push_back(i);
  }
  std::vector<Counts> counts(bands);
  for (int phase = 0; phase < cfg_.phases; ++phase) {
    std::vector<int> mine;
    for (int b = phase; b < bands; b += cfg_.phases)
      if (!band_agents_[b].empty()) mine.push_back(b);
    GDRHCR_TSAN_RELEASE(this);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, mine.size(), 1),
        [&](const tbb::blocked_range<size_t>& r) {
          GDRHCR_TSAN_ACQUIRE(this);
          for (size_t k = r.begin(); k != r.end(); ++k) {
            const int b = mine[k];
            const uint64_t draw = mix_seed(mix_seed(cfg_.seed, static_cast<uint64_t>(now)), static_cast<uint64_t>(b));
            std::minstd_rand rng(static_cast<std::minstd_rand::result_type>(draw % 2147483646u + 1));
            Search& search = parallel_->search.local();
            update_in_order(world, band_agents_[b], deadline, search, rng, counts[b]);
            refine(world, band_agents_[b], deadline, refine_until, search, rng, counts[b]);
          }
          GDRHCR_TSAN_RELEASE(this);
        },
        tbb::simple_partitioner());
    GDRHCR_TSAN_ACQUIRE(this);
  }
  for (auto& c : counts) counts_.add(c);
}

void LocalGuidance::Marks::start(size_t pairs) {
  const bool hash = pairs * sizeof(Mark) > kDirectMarksBytes;
  if (table.empty() || hash != hashed || (!hash && table.size() != pairs)) {
    hashed = hash;
    bits = 10;
    table.assign(hash ? size_t{1} << bits : pairs, Mark{0, 0.f});
    keys.assign(hash ? table.size() : 0, 0);
    stamp = 0;
  }
  if (++stamp >= (1u << 31)) {  // tags are 2 x stamp (+ 1): start over before they wrap
    std::fill(table.begin(), table.end(), Mark{0, 0.f});
    stamp = 1;
  }
  used = 0;
}

[[gnu::always_inline]] inline LocalGuidance::Mark& LocalGuidance::Marks::find(uint32_t key) {
  if (!hashed) return table[key];
  const uint32_t live = 2 * stamp;
  for (;;) {
    const size_t mask = table.size() - 1;
    for (size_t h = (key * 0x9E3779B1u) >> (32 - bits);; h = (h + 1) & mask) {
      Mark& m = table[h];
      if (m.tag >= live) {  // taken in this search
        if (keys[h] == key) return m;
        continue;
      }
      if (2 * (used + 1) > table.size()) break;  // at most half full
      ++used;
      m = Mark{live - 2, 0.f};  // unseen by this search
      keys[h] = key;
      return m;
    }
    grow();
  }
}

// Doubles the hashed table, keeping this search's entries.
void LocalGuidance::Marks::grow() {
  std::vector<Mark> old(size_t{1} << (bits + 1), Mark{0, 0.f});
  std::vector<uint32_t> old_keys(old.size(), 0);
  old.swap(table);
  old_keys.swap(keys);
  ++bits;
  const uint32_t live = 2 * stamp;
  const size_t mask = table.size() - 1;
  for (size_t k = 0; k < old.size(); ++k) {
    if (old[k].tag < live) continue;
    size_t h = (old_keys[k] * 0x9E3779B1u) >> (32 - bits);
    while (table[h].tag >= live) h = (h + 1) & mask;
    table[h] = old[k];
    keys[h] = old_keys[k];
  }
}

// The moves out of (v, h) other than a wait, in a random order, so equally good paths do not all
// bend the same way: the free neighbours (mapf), or forward and the two quarter turns (rotation).
[[gnu::always_inline]] inline int LocalGuidance::moves(Cell v, Heading h, bool rot, std::minstd_rand& rng, Cell* nb,
                                                      Heading* nh) const {
  int m = 0;
  if (rot) {
    if (const Cell u = forward_cell(grid_, v, h); u != kNoCell) nb[m] = u, nh[m++] = h;
    nb[m] = v, nh[m++] = rotate_cw(h);
    nb[m] = v, nh[m++] = rotate_ccw(h);
  } else {
    // Mapf: the heading of the move, for lg-straight's tie break only (the search's states are cells).
    for (Cell u : grid_.neighbours(v)) {
      if (m == 4) break;  // a grid cell has at most four neighbours (bounds the writes for the compiler)
      nb[m] = u, nh[m++] = cfg_.straight ? heading_of_move(grid_, v, u) : kNoHeading;
    }
  }
  for (int a = m - 1; a > 0; --a) {
    const auto r = rng();  // r % (a + 1), with a constant divisor for each of the few a
    const int b = static_cast<int>(a == 3 ? r % 4 : a == 2 ? r % 3 : a == 1 ? r % 2 : r % (a + 1));
    std::swap(nb[a], nb[b]), std::swap(nh[a], nh[b]);
  }
  return m;
}

// Space-time A* over (t, cell), t = 0..W: cost 1 per step plus its collision penalty (meeting
// other paths); heuristic the distance to the goal. In the rotation model over (t, cell,
// heading): forward into the faced cell, a quarter turn or a wait, one step each (a turn pays as
// a wait), heuristic the distance with turns; the path keeps only the cells (a turn repeats one).
// Among equal f the deeper node goes first, so free paths are found almost without branching.
void LocalGuidance::plan(const WorldView& world, int i, Search& search, std::minstd_rand& rng, Counts& counts) {
  ++counts.searches;
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
  const bool rot = world.rotation();
  const int states = rot ? kNumHeadings : 1;
  auto& marks = search.marks;
  marks.start(static_cast<size_t>(slots_) * grid_.num_cells() * states);
  auto& nodes = search.nodes;
  auto& open = search.open;
  const uint32_t seen = 2 * marks.stamp, closed = seen + 1;
  auto key = [&](Cell v, Heading hd, int t) {
    const uint32_t state = rot ? static_cast<uint32_t>(v) * 4 + static_cast<uint32_t>(hd) : static_cast<uint32_t>(v);
    return state * static_cast<uint32_t>(slots_) + static_cast<uint32_t>(t);
  };
  auto dist_of = [&](Cell v, Heading hd) { return rot ? row.at(v, hd) : row[v]; };
  nodes.clear();
  open.clear();
  const Heading h0 = rot ? world.pose(i).heading : kNoHeading;
  nodes.push_back({0.f, static_cast<float>(dist_of(at, h0)), 0, at, -1, h0});
  open.push(nodes[0].f, 0, 0);
  int32_t best = 0;
  int expanded = 0;
  while (!open.empty()) {
    const int32_t id = open.pop();
    const Node n = nodes[id];
    Mark& mark = marks.find(key(n.v, n.h, n.t));
    if (mark.tag == closed) continue;
    mark.tag = closed;
    // Done on the goal (the agent gets its next goal there): that path, even when a deeper node
    // was popped before it. Such a node is no cheaper and does not reach the goal; following
    // it (waiting beside a goal another agent rests on, where stepping in costs a collision at
    // every time) kept an agent off that goal for ever. PIBT pushes the resting agent away.
    if (n.v == goal) {
      best = id;
      break;
    }
    if (n.t > nodes[best].t || (n.t == nodes[best].t && n.f < nodes[best].f)) best = id;
    // Done at the window's end (or out of expansions: the deepest cheapest node so far).
    if (n.t == W || ++expanded > cfg_.max_expansions) break;
    const int s = slot(world.timestep + n.t), s1 = s + 1 == slots_ ? 0 : s + 1;
    auto expand = [&](Cell u, Heading hd) {
      Mark& mk = marks.find(key(u, hd, n.t + 1));
      if (mk.tag == closed) return;
      const int h = dist_of(u, hd);
      if (h >= kUnreachable) return;
      const bool turned = !rot && u != n.v && n.h != kNoHeading && hd != n.h;  // lg-straight only
      const float g = n.g + 1.f + collision_penalty(n.v, u, s, s1, n.t) +
                      (turned ? LocalGuidanceConfig::kStraightTieBreak : 0.f);
      if (mk.tag == seen && mk.best_g <= g) return;  // reached as cheaply before
      mk.tag = seen;
      mk.best_g = g;
      Node& c = nodes.emplace_back();  // field by field: a whole Node stored and read back stalls
      c.g = g, c.f = g + h, c.t = n.t + 1, c.v = u, c.parent = id, c.h = hd;
      open.push(g + h, n.t + 1, static_cast<int32_t>(nodes.size() - 1));
    };
    Cell nb[4];
    Heading nh[4];
    const int m = moves(n.v, n.h, rot, rng, nb, nh);
    for (int a = 0; a < m; ++a) expand(nb[a], nh[a]);
    expand(n.v, n.h);
  }
  counts.expansions += expanded;
  out.assign(nodes[best].t + 1, kNoCell);
  for (int32_t k = best; k >= 0; k = nodes[k].parent) out[nodes[k].t] = nodes[k].v;
}

Cell LocalGuidance::next_cell(int i, int now, Cell at) const {
  const auto& p = path_[i];
  if (p.size() < 2 || start_[i] != now || p[0] != at) return kNoCell;
  return p[1];
}

Cell LocalGuidance::next_move(int i, int now, Cell at) const {
  const auto& p = path_[i];
  if (p.size() < 2 || start_[i] != now || p[0] != at) return kNoCell;
  for (size_t k = 1; k < p.size() && k <= static_cast<size_t>(kTurnLookahead); ++k)
    if (p[k] != at) return p[k];
  return at;
}

std::vector<Cell> LocalGuidance::path_from(int i, int now) const {
  const auto& p = path_[i];
  const int k = now - start_[i];
  if (p.empty() || k < 0 || k >= static_cast<int>(p.size())) return {};
  return std::vector<Cell>(p.begin() + k, p.end());
}

}  // namespace gdrhcr
