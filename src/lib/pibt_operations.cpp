// PIBT in the rotation action model, over short operations (see pibt.hpp). After EPIBT (Nagorny
// et al., "EPIBT", LoRR 2024, arXiv 2511.09193) and PIBT (Okumura et al., AIJ 2022).
#include <algorithm>
#include <array>
#include <chrono>
#include <climits>

#include "gdrhcr/pibt.hpp"

namespace gdrhcr {

namespace {
constexpr int kFree = -1;
constexpr int kFixed = -2;  // a cell held by an agent outside the call (or blocked)

using Operation = std::array<Action, PibtStep::kOpSteps>;

// Every sequence of kOpSteps actions except: a turn right after the opposite one (they cancel),
// two counter-clockwise turns in a row (two clockwise ones reach the same state), and a turn as
// the last action (the next step plans again; the same operation ending in a wait holds the same
// cells).
std::vector<Operation> make_operations() {
  constexpr Action kAll[4] = {Action::kForward, Action::kClockwise, Action::kCounterClockwise, Action::kWait};
  auto turn = [](Action a) { return a == Action::kClockwise || a == Action::kCounterClockwise; };
  std::vector<Operation> ops;
  Operation op{};
  for (int code = 0; code < 64; ++code) {
    for (int k = 0, c = code; k < PibtStep::kOpSteps; ++k, c /= 4) op[k] = kAll[c % 4];
    bool keep = !turn(op[PibtStep::kOpSteps - 1]);
    for (int k = 1; k < PibtStep::kOpSteps && keep; ++k)
      keep = !(turn(op[k - 1]) && turn(op[k]) && (op[k] != op[k - 1] || op[k] == Action::kCounterClockwise));
    if (keep) ops.push_back(op);
  }
  return ops;
}

const std::vector<Operation>& operations() {
  static const std::vector<Operation> ops = make_operations();
  return ops;
}
constexpr int kMaxOps = 64;
}  // namespace

void PibtStep::set_res(int k, Cell c, int v) {
  int& slot = res(k, c);
  undo_ints_.emplace_back(&slot, slot);
  slot = v;
}

void PibtStep::reserve(int ai, const OpPath& p) {
  undo_paths_.emplace_back(ai, op_path_[ai]);
  op_path_[ai] = p;
  for (int k = 1; k <= kOpSteps; ++k) set_res(k, p.cell[k], ai);
}

void PibtStep::release(int ai) {
  const OpPath& p = op_path_[ai];
  for (int k = 1; k <= kOpSteps; ++k)
    if (res(k, p.cell[k]) == ai) set_res(k, p.cell[k], kFree);
}

void PibtStep::rollback(size_t ints, size_t paths) {
  while (undo_ints_.size() > ints) *undo_ints_.back().first = undo_ints_.back().second, undo_ints_.pop_back();
  while (undo_paths_.size() > paths) op_path_[undo_paths_.back().first] = undo_paths_.back().second, undo_paths_.pop_back();
}

// The agents operation p of ai displaces (cells they hold at the same step, or moves crossing
// ai's), into out[0..m). False when p meets a fixed cell or an agent planned already.
bool PibtStep::conflicts_of(int ai, const OpPath& p, int* out, int& m) const {
  m = 0;
  auto add = [&](int v) {
    if (locked_[v] == lock_stamp_) return false;  // planned already: it keeps its operation
    if (std::find(out, out + m, v) == out + m) out[m++] = v;
    return true;
  };
  for (int k = 1; k <= kOpSteps; ++k) {
    const Cell c = p.cell[k], before = p.cell[k - 1];
    const int v = res(k, c);
    if (v == kFixed) return false;
    if (v >= 0 && v != ai && !add(v)) return false;
    if (before == c) continue;
    const int u = k == 1 ? occupied_now_[c] : res(k - 1, c);  // who is at c before ai gets there
    if (u >= 0 && u != ai && res(k, before) == u && !add(u)) return false;
  }
  return true;
}

// ai's operations that stay on free cells, best first: one starting with the preferred cell's
// action (a guidance path), then by the goal reached earliest or the distance with turns from
// the final state, then (kFreeFirst) the fewest cells held by others, then the fewest leading
// waits (without it, an agent asked to give way chose to wait first and was asked again at the
// next step, for ever), then the earliest progress, then at random.
int PibtStep::order_operations(const WorldView& world, int ai, OpPath* paths) {
  const Pose start = world.pose(ai);
  const DistRow& row = *rows_[ai];
  const Cell pref = preferred_ ? (*preferred_)[ai] : kNoCell;
  const Heading pref_h = pref == kNoCell ? kNoHeading : heading_of_move(grid_, start.cell, pref);
  const bool free_first = opt_.tie_break != PibtOptions::TieBreak::kRandom;
  std::array<std::pair<long long, int>, kMaxOps> keyed;
  int m = 0;
  for (const Operation& op : operations()) {
    OpPath& p = paths[m];
    Pose q = start;
    p.cell[0] = q.cell, p.heading[0] = q.heading;
    int reached = -1, sum = 0, busy = 0;
    bool ok = true;
    for (int k = 1; k <= kOpSteps && ok; ++k) {
      q = apply_action(grid_, q, op[k - 1]);
      ok = q.cell != kNoCell;
      if (!ok) break;
      p.cell[k] = q.cell, p.heading[k] = q.heading;
      const int d = std::min(row.at(q.cell, q.heading), 1 << 20);
      if (q.cell == goal_of_[ai] && reached < 0) reached = k;
      sum += d;
      const int v = res(k, q.cell);
      busy += v == kFixed || (v >= 0 && v != ai);
    }
    if (!ok) continue;
    bool preferred = false;
    if (pref == start.cell) preferred = op[0] == Action::kWait;
    else if (pref_h != kNoHeading)
      preferred = op[0] == Action::kForward ? pref_h == start.heading
                  : op[0] != Action::kWait && turn_steps(p.heading[1], pref_h) < turn_steps(start.heading, pref_h);
    const long long cost = reached >= 0 ? reached : kOpSteps + 1 + std::min(row.at(q.cell, q.heading), 1 << 20);
    int waits = 0;  // leading waits: an agent giving way that puts it off is asked again next step
    while (waits < kOpSteps && op[waits] == Action::kWait) ++waits;
    keyed[m] = {((preferred ? 0LL : 1LL) << 50) + (cost << 26) + ((free_first ? busy : 0) << 23) +
                    (static_cast<long long>(waits) << 21) + std::min(sum, (1 << 21) - 1),
                m};
    ++m;
  }
  std::shuffle(keyed.begin(), keyed.begin() + m, rng_);
  std::stable_sort(keyed.begin(), keyed.begin() + m);
  OpPath sorted[kMaxOps];
  for (int k = 0; k < m; ++k) sorted[k] = paths[keyed[k].second];
  std::copy(sorted, sorted + m, paths);
  return m;
}

// Plans ai (displaced, or next in priority order): its best operation whose displaced agents can
// all be planned around it. On failure everything it changed is left for the caller to undo.
bool PibtStep::plan_operation(const WorldView& world, int ai, int depth) {
  if (++op_plans_ > kOpBudget) return false;
  undo_ints_.emplace_back(&locked_[ai], locked_[ai]);
  locked_[ai] = lock_stamp_;
  release(ai);
  OpPath cand[kMaxOps];
  const int m = order_operations(world, ai, cand);
  int displaced[2 * kOpSteps];
  for (int c = 0; c < m; ++c) {
    int nd = 0;
    if (!conflicts_of(ai, cand[c], displaced, nd) || (nd > 0 && depth >= kOpDepth)) continue;
    const size_t ints = undo_ints_.size(), paths = undo_paths_.size();
    for (int k = 0; k < nd; ++k) release(displaced[k]);
    reserve(ai, cand[c]);
    bool ok = true;
    for (int k = 0; k < nd && ok; ++k) ok = plan_operation(world, displaced[k], depth + 1);
    if (ok) return true;
    rollback(ints, paths);
    if (op_plans_ > kOpBudget) break;
  }
  return false;
}

// The step in the rotation model: every agent of the call holds its cell, agents outside it and
// blocked cells are fixed, then the main loop plans agents in priority order; each agent's first
// action is its move.
void PibtStep::plan_operations(const WorldView& world, std::vector<Cell>& next,
                               const std::vector<std::pair<Cell, Cell>>& fixed_moves) {
  const int n = world.num_agents();
  res_.resize(size_t(kOpSteps) * grid_.num_cells(), kFree);
  op_path_.resize(n);
  locked_.resize(n, 0);
  if (++lock_stamp_ == INT_MAX) std::fill(locked_.begin(), locked_.end(), 0), lock_stamp_ = 1;
  auto fix = [&](Cell c, int from_k) {
    for (int k = from_k; c != kNoCell && k <= kOpSteps; ++k) res(k, c) = kFixed;
  };
  for (auto& [from, to] : fixed_moves) {
    if (from != kNoCell) res(1, from) = kFixed;
    fix(to, 1);
  }
  if (world.blocked)
    for (Cell c : *world.blocked) fix(c, 1);
  for (int i : order_) {
    const Pose p = world.pose(i);
    for (int k = 0; k <= kOpSteps; ++k) op_path_[i].cell[k] = p.cell, op_path_[i].heading[k] = p.heading;
    for (int k = 1; k <= kOpSteps; ++k) res(k, p.cell) = i;
    if (world.is_immovable(i)) locked_[i] = lock_stamp_;
  }
  std::stable_sort(order_.begin(), order_.end(), [&](int a, int b) { return priority_[a] > priority_[b]; });
  const bool timed = deadline_ != std::chrono::steady_clock::time_point::max();
  for (int i : order_) {
    if (locked_[i] == lock_stamp_) continue;
    if (timed && std::chrono::steady_clock::now() >= deadline_) {  // the rest hold their cells (WWW)
      ++deadline_stops_;
      break;
    }
    op_plans_ = 0;
    if (!plan_operation(world, i, 0)) rollback(0, 0);
    locked_[i] = lock_stamp_;
    undo_ints_.clear();
    undo_paths_.clear();
  }
  for (int i : order_) {
    next[i] = op_path_[i].cell[1];
    (*world.next_headings)[i] = op_path_[i].heading[1];
    for (int k = 1; k <= kOpSteps; ++k) res(k, op_path_[i].cell[k]) = kFree;
  }
  for (auto& [from, to] : fixed_moves)
    for (Cell c : {from, to})
      for (int k = 1; c != kNoCell && k <= kOpSteps; ++k) res(k, c) = kFree;
  if (world.blocked)
    for (Cell c : *world.blocked)
      for (int k = 1; k <= kOpSteps; ++k) res(k, c) = kFree;
}

}  // namespace gdrhcr
