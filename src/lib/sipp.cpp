// SIPP with a horizon, goal sequences and soft constraints: see sipp.hpp.
// Phillips, Likhachev, "SIPP: Safe Interval Path Planning for Dynamic Environments", ICRA 2011;
// RHCR (Li et al., AAAI 2021) windowed low level; GD-RHCR (DeWeese, Li, Qu) soft constraints.
#include "gdrhcr/sipp.hpp"

#include <algorithm>
#include <stdexcept>

namespace gdrhcr {

// ---------------------------------------------------------------------------------------------
// ConstraintTable

ConstraintTable::ConstraintTable(const Grid& grid, int horizon)
    : grid_(grid),
      horizon_(horizon),
      words_((std::max(horizon, 0) + 1 + 63) / 64),
      vertex_(size_t(grid.num_cells()) * words_, 0),
      move_(size_t(grid.num_cells()) * 4 * words_, 0),
      touched_flag_(grid.num_cells(), 0) {
  if (horizon < 0) throw std::invalid_argument("constraint table: negative horizon");
}

void ConstraintTable::touch(Cell c) {
  if (touched_flag_[c]) return;
  touched_flag_[c] = 1;
  touched_.push_back(c);
}

void ConstraintTable::block_vertex(Cell c, int t) {
  if (t < 0 || t > horizon_) return;
  touch(c);
  vertex_[size_t(c) * words_ + (t >> 6)] |= uint64_t(1) << (t & 63);
}

void ConstraintTable::block_move(Cell from, Cell to, int t) {
  if (t < 0 || t >= horizon_ || from == to) return;
  touch(from);
  move_[(size_t(from) * 4 + dir(from, to)) * words_ + (t >> 6)] |= uint64_t(1) << (t & 63);
}

void ConstraintTable::add_path(const std::vector<Cell>& path) {
  if (path.empty()) return;
  const int last = static_cast<int>(path.size()) - 1;
  auto at = [&](int t) { return path[std::min(t, last)]; };
  for (int t = 0; t <= horizon_; ++t) block_vertex(at(t), t);
  // A move p -> q at t forbids the swap q -> p at t.
  for (int t = 0; t < horizon_ && t < last; ++t)
    if (at(t) != at(t + 1)) block_move(at(t + 1), at(t), t);
}

bool ConstraintTable::violated_by(const std::vector<Cell>& path) const {
  if (path.empty()) return false;
  const int last = static_cast<int>(path.size()) - 1;
  auto at = [&](int t) { return path[std::min(t, last)]; };
  for (int t = 0; t <= horizon_; ++t) {
    if (!cell_constrained(at(t))) continue;
    if (vertex_blocked(at(t), t)) return true;
    if (t < horizon_ && at(t) != at(t + 1) && move_blocked(at(t), at(t + 1), t)) return true;
  }
  return false;
}

void ConstraintTable::clear() {
  for (Cell c : touched_) {
    std::fill_n(&vertex_[size_t(c) * words_], words_, 0);
    std::fill_n(&move_[size_t(c) * 4 * words_], 4 * words_, 0);
    touched_flag_[c] = 0;
  }
  touched_.clear();
}

// ---------------------------------------------------------------------------------------------
// SippAgent

SippAgent::SippAgent(const DistTable& dist, Cell s, const std::vector<Cell>& all_goals, int horizon, Heading h)
    : start(s), heading(dist.action_model() == ActionModel::kRotation ? h : kNoHeading) {
  // Keep goals while they are reachable and could still be reached before the horizon: the
  // first goal whose earliest arrival is >= H is the last one that changes the search (later
  // ones only add a constant to the cost of every node that matters).
  long lower_bound = 0;
  Cell from = start;
  for (Cell g : all_goals) {
    auto row = dist.row(g);
    const int d = (*row)[from];
    if (d >= kUnreachable) break;
    goals.push_back(g);
    rows.push_back(std::move(row));
    lower_bound += d;
    from = g;
    if (lower_bound >= horizon) break;
  }
  goal0_reachable = !all_goals.empty() && !goals.empty();
  tail.assign(goals.size(), 0);
  for (int k = static_cast<int>(goals.size()) - 2; k >= 0; --k)
    tail[k] = tail[k + 1] + (*rows[k + 1])[goals[k]];
}

// ---------------------------------------------------------------------------------------------
// Sipp

namespace {
constexpr int kInf = std::numeric_limits<int>::max() / 4;

struct Interval {
  int lo, hi;  // arrival times [lo, hi]; hi = kInf for the last one
  int k;       // soft vertex count, constant over the interval
  int labels;  // nodes that reached this interval (linked through Node::next_label)
};

struct Node {
  Cell cell;
  Heading heading;  // rotation; kNoHeading in mapf
  int ival;  // index into the interval arena
  int gi;    // goals visited so far
  int t;     // arrival time
  int conf;  // soft conflicts so far
  int parent;
  int next_label;
  bool dead;  // dominated by a later-generated node: skip when popped
};

struct HeapItem {
  double f;
  int conf;
  int t;
  int idx;
  // Min-heap on (f, conflicts), deeper first among equals to reach the horizon sooner.
  bool operator<(const HeapItem& o) const {
    if (f != o.f) return f > o.f;
    if (conf != o.conf) return conf > o.conf;
    return t < o.t;
  }
};
}  // namespace

struct Sipp::Impl {
  explicit Impl(const Grid& g)
      : grid(g), stamp(g.num_cells(), 0), ival_begin(g.num_cells(), 0), ival_count(g.num_cells(), 0) {}

  const Grid& grid;
  std::vector<uint32_t> stamp;  // intervals of cell c are valid this call when stamp[c] == call
  uint32_t call = 0;
  std::vector<int32_t> ival_begin, ival_count;
  std::vector<Interval> ivals;
  std::vector<Node> nodes;
  std::vector<HeapItem> heap;
  std::vector<int> counts;

  // Per-call inputs.
  const SippAgent* agent = nullptr;
  const ConstraintTable* hard = nullptr;
  const SoftConstraintTable* soft = nullptr;
  double c_soft = 0;
  int H = 0;
  int m = 0;

  int h(Cell c, Heading hd, int gi) const {
    if (gi >= m) return 0;
    return (hd == kNoHeading ? (*agent->rows[gi])[c] : agent->rows[gi]->at(c, hd)) + agent->tail[gi];
  }
  int advance(Cell c, int gi) const {
    while (gi < m && agent->goals[gi] == c) ++gi;
    return gi;
  }
  void intervals_of(Cell c);
  void push(Cell v, Heading hd, int ival, int gi, int t, int conf, int parent);
  void expand_moves(const Node& n, int idx);
  void expand_turns(const Node& n, int idx);
  SippResult run(const SippLimits& limits);
  void finish(int idx, SippResult& r) const;
  void finish_rotation(int idx, SippResult& r) const;
};

void Sipp::Impl::intervals_of(Cell c) {
  if (stamp[c] == call) return;
  stamp[c] = call;
  ival_begin[c] = static_cast<int32_t>(ivals.size());
  const bool hard_any = hard->cell_constrained(c);
  const bool soft_any = soft && soft->touches(c);
  if (!hard_any && !soft_any) {
    ivals.push_back({0, kInf, 0, -1});
    ival_count[c] = 1;
    return;
  }
  counts.assign(H + 1, 0);
  if (soft_any) soft->add_vertex_counts(c, H, counts.data());
  auto blocked = [&](int t) { return hard_any && hard->vertex_blocked(c, t); };
  for (int t = 0; t <= H; ++t) {
    if (blocked(t)) continue;
    const int lo = t, k = counts[t];
    while (t + 1 <= H && !blocked(t + 1) && counts[t + 1] == k) ++t;
    // Past the horizon nothing is constrained: a conflict-free run reaching H never ends.
    ivals.push_back({lo, (t == H && k == 0) ? kInf : t, k, -1});
  }
  if (ivals.size() == size_t(ival_begin[c]) || ivals.back().hi != kInf)
    ivals.push_back({H + 1, kInf, 0, -1});
  ival_count[c] = static_cast<int32_t>(ivals.size()) - ival_begin[c];
}

void Sipp::Impl::push(Cell v, Heading hd, int ival, int gi, int t, int conf, int parent) {
  const int k = ivals[ival].k;
  // Dominance within one (cell, heading, interval, goal index): an earlier arrival can wait,
  // paying k conflicts per step; it dominates if it is then no worse in conflicts.
  for (int l = ivals[ival].labels; l >= 0; l = nodes[l].next_label) {
    const Node& o = nodes[l];
    if (o.dead || o.gi != gi || o.heading != hd) continue;
    if (o.t <= t && o.conf + long(k) * (t - o.t) <= conf) return;
  }
  for (int l = ivals[ival].labels; l >= 0; l = nodes[l].next_label) {
    Node& o = nodes[l];
    if (!o.dead && o.gi == gi && o.heading == hd && t <= o.t && conf + long(k) * (o.t - t) <= o.conf) o.dead = true;
  }
  const int idx = static_cast<int>(nodes.size());
  nodes.push_back({v, hd, ival, gi, t, conf, parent, ivals[ival].labels, false});
  ivals[ival].labels = idx;
  heap.push_back({double(t + h(v, hd, gi)) + c_soft * conf, conf, t, idx});
  std::push_heap(heap.begin(), heap.end());
}

// Moves into a neighbour (mapf: any; rotation: the faced one, keeping the heading), departing at
// any time of the node's interval that arrives inside one of the neighbour's intervals.
void Sipp::Impl::expand_moves(const Node& n, int idx) {
  const Interval I = ivals[n.ival];
  const bool use_soft = soft != nullptr;
  auto to = [&](Cell v) {
    intervals_of(v);
    const int b = ival_begin[v], e = b + ival_count[v];
    for (int j = b; j < e; ++j) {
      const Interval J = ivals[j];
      if (J.hi < n.t + 1) continue;
      if (J.lo > I.hi + 1) break;
      // Depart at d (waiting in I until then), arrive at d + 1 inside J.
      for (int d = std::max(n.t, J.lo - 1); d <= I.hi && d + 1 <= J.hi; ++d) {
        if (hard->move_blocked(n.cell, v, d)) continue;
        const int swaps = (use_soft && d < H) ? soft->edge_count(n.cell, v, d) : 0;
        push(v, n.heading, j, advance(v, n.gi), d + 1, n.conf + I.k * (d - n.t) + J.k + swaps, idx);
        // A later departure can only pay off by avoiding a soft swap.
        if (swaps == 0) break;
      }
    }
  };
  if (n.heading == kNoHeading) {
    for (Cell v : grid.neighbours(n.cell)) to(v);
  } else if (const Cell v = forward_cell(grid, n.cell, n.heading); v != kNoCell) {
    to(v);
  }
}

// Rotation: a quarter turn either way takes one step in the same cell and interval.
void Sipp::Impl::expand_turns(const Node& n, int idx) {
  const Interval I = ivals[n.ival];
  if (n.heading == kNoHeading || n.t + 1 > I.hi) return;
  for (Heading hd : {rotate_cw(n.heading), rotate_ccw(n.heading)})
    push(n.cell, hd, n.ival, n.gi, n.t + 1, n.conf + I.k, idx);
}

SippResult Sipp::Impl::run(const SippLimits& limits) {
  SippResult r;
  const Cell s = agent->start;
  intervals_of(s);
  const Interval& first = ivals[ival_begin[s]];
  if (first.lo != 0) return r;  // the start itself is taken at t = 0 by a higher-priority agent
  push(s, agent->heading, ival_begin[s], advance(s, 0), 0, first.k, -1);

  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end());
    const int idx = heap.back().idx;
    heap.pop_back();
    const Node n = nodes[idx];
    if (n.dead) continue;
    const Interval I = ivals[n.ival];
    // Past H the heuristic is exact, and a finished agent in an endless interval is parked.
    if (n.t >= H || (n.gi == m && I.hi == kInf)) {
      finish(idx, r);
      return r;
    }
    if (limits.expansion_budget > 0 && r.expansions >= limits.expansion_budget) break;
    if ((r.expansions & 255) == 255 && std::chrono::steady_clock::now() > limits.deadline) break;
    ++r.expansions;

    expand_moves(n, idx);
    expand_turns(n, idx);
    // Waiting across a soft boundary into the adjoining interval of the same cell.
    const int next = n.ival + 1;
    if (I.hi != kInf && next < ival_begin[n.cell] + ival_count[n.cell] && ivals[next].lo == I.hi + 1)
      push(n.cell, n.heading, next, n.gi, I.hi + 1, n.conf + I.k * (I.hi - n.t) + ivals[next].k, idx);
  }
  r.cut_short = !heap.empty();
  return r;
}

void Sipp::Impl::finish(int idx, SippResult& r) const {
  if (agent->heading != kNoHeading) return finish_rotation(idx, r);
  const Node& goal = nodes[idx];
  std::vector<int> chain;
  for (int i = idx; i >= 0; i = nodes[i].parent) chain.push_back(i);
  std::reverse(chain.begin(), chain.end());
  r.path.clear();
  r.path.push_back(nodes[chain[0]].cell);
  for (size_t i = 1; i < chain.size(); ++i) {
    const Node& a = nodes[chain[i - 1]];
    const Node& b = nodes[chain[i]];
    while (static_cast<int>(r.path.size()) < b.t) r.path.push_back(a.cell);  // waits
    r.path.push_back(b.cell);
  }
  // Past the horizon: finish the way to goals[0] on a shortest path (nothing constrains it).
  if (goal.gi == 0 && m > 0) {
    const DistRow& row = *agent->rows[0];
    Cell c = goal.cell;
    while (c != agent->goals[0]) {
      for (Cell nb : grid.neighbours(c))
        if (row[nb] == row[c] - 1) { c = nb; break; }
      r.path.push_back(c);
    }
  }
  while (static_cast<int>(r.path.size()) < H + 1) r.path.push_back(r.path.back());
  r.found = true;
  r.soft_conflicts = goal.conf;
  r.cost = double(goal.t + h(goal.cell, goal.heading, goal.gi)) + c_soft * goal.conf;
}

// The same with headings: a turn changes the heading in place, a wait keeps it, and past the
// horizon the way to goals[0] follows the rotation row (forward first among equal actions).
void Sipp::Impl::finish_rotation(int idx, SippResult& r) const {
  const Node& goal = nodes[idx];
  std::vector<int> chain;
  for (int i = idx; i >= 0; i = nodes[i].parent) chain.push_back(i);
  std::reverse(chain.begin(), chain.end());
  r.path.assign(1, nodes[chain[0]].cell);
  r.headings.assign(1, nodes[chain[0]].heading);
  for (size_t i = 1; i < chain.size(); ++i) {
    const Node& a = nodes[chain[i - 1]];
    const Node& b = nodes[chain[i]];
    while (static_cast<int>(r.path.size()) < b.t) r.path.push_back(a.cell), r.headings.push_back(a.heading);
    r.path.push_back(b.cell);
    r.headings.push_back(b.heading);
  }
  if (goal.gi == 0 && m > 0) {
    const DistRow& row = *agent->rows[0];
    Pose p{goal.cell, goal.heading};
    for (int d = row.at(p.cell, p.heading); d > 0 && d < kUnreachable; --d) {
      for (Action act : {Action::kForward, Action::kClockwise, Action::kCounterClockwise}) {
        const Pose q = apply_action(grid, p, act);
        if (q.cell != kNoCell && row.at(q.cell, q.heading) == d - 1) {
          p = q;
          break;
        }
      }
      r.path.push_back(p.cell);
      r.headings.push_back(p.heading);
    }
  }
  while (static_cast<int>(r.path.size()) < H + 1) r.path.push_back(r.path.back()), r.headings.push_back(r.headings.back());
  r.found = true;
  r.soft_conflicts = goal.conf;
  r.cost = double(goal.t + h(goal.cell, goal.heading, goal.gi)) + c_soft * goal.conf;
}

Sipp::Sipp(const Grid& grid) : impl_(std::make_unique<Impl>(grid)) {}
Sipp::~Sipp() = default;

SippResult Sipp::plan(const SippAgent& agent, const ConstraintTable& hard,
                      const SoftConstraintTable* soft, double c_soft, const SippLimits& limits) {
  Impl& s = *impl_;
  if (&hard.grid() != &s.grid)
    throw std::invalid_argument("SIPP: constraint table built for another grid");
  if (++s.call == 0) {  // stamp wrap-around: invalidate every cell explicitly
    std::fill(s.stamp.begin(), s.stamp.end(), 0);
    s.call = 1;
  }
  s.ivals.clear();
  s.nodes.clear();
  s.heap.clear();
  s.agent = &agent;
  s.hard = &hard;
  // With c_soft = 0 conflicts cost nothing: search without them, count them afterwards.
  s.soft = (soft && !soft->empty() && c_soft > 0) ? soft : nullptr;
  s.c_soft = s.soft ? c_soft : 0;
  s.H = hard.horizon();
  s.m = static_cast<int>(agent.goals.size());
  SippResult r = s.run(limits);
  if (r.found && soft && !s.soft) r.soft_conflicts = count_soft_conflicts(r.path, *soft, s.H);
  return r;
}

SippResult Sipp::plan(const DistTable& dist, Cell start, const std::vector<Cell>& goals,
                      const ConstraintTable& hard, const SoftConstraintTable* soft, double c_soft,
                      const SippLimits& limits) {
  const SippAgent agent(dist, start, goals, hard.horizon());
  return plan(agent, hard, soft, c_soft, limits);
}

int count_soft_conflicts(const std::vector<Cell>& path, const SoftConstraintTable& soft, int horizon) {
  if (path.empty() || soft.empty()) return 0;
  const int last = static_cast<int>(path.size()) - 1;
  auto at = [&](int t) { return path[std::min(t, last)]; };
  int n = 0;
  for (int t = 0; t <= horizon; ++t) {
    n += soft.vertex_count(at(t), t);
    if (t < horizon) n += soft.edge_count(at(t), at(t + 1), t);
  }
  return n;
}

}  // namespace gdrhcr
