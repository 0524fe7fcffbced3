#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/lanes.hpp"
#include "tsan_annotations.hpp"

#include <algorithm>
#include <cstring>
#include <cmath>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace gdrhcr {


namespace {
// What a cache entry costs besides its row: the Entry, and the hash node (key, pointer, next).
constexpr size_t kEntryOverhead = sizeof(std::atomic<uint64_t>) + sizeof(std::shared_ptr<const DistRow>) +
                                  sizeof(Cell) + 2 * sizeof(void*);
}  // namespace

FreeCellIndex::FreeCellIndex(const Grid& grid, const std::vector<Cell>& blocked_cells, ActionModel m,
                             StepCosts costs)
    : model(m) {
  const auto& free = grid.free_cells();
  num_free = static_cast<int32_t>(free.size());
  cell_of = free;
  slot_of.assign(grid.num_cells(), num_free);
  for (int32_t s = 0; s < num_free; ++s) slot_of[free[s]] = s;
  adj_begin.resize(size_t(num_free) + 1);
  adj.reserve(size_t(num_free) * 4);
  for (int32_t s = 0; s < num_free; ++s) {
    adj_begin[s] = static_cast<int32_t>(adj.size());
    for (Cell n : grid.neighbours(free[s])) adj.push_back(slot_of[n]);
  }
  adj_begin[num_free] = static_cast<int32_t>(adj.size());
  adj.shrink_to_fit();
  if (!blocked_cells.empty()) {
    blocked.assign(num_free, 0);
    for (Cell c : blocked_cells)
      if (grid.is_free(c)) blocked[slot_of[c]] = 1;
  }
  if (costs.any()) {
    // The rotation model only: the mapf model's SIPP runs out of memory on costed rows.
    if (model != ActionModel::kRotation)
      throw std::invalid_argument("traffic-cost, lane-cost and open-cost apply to the rotation model only");
    cost.assign(size_t(num_free) * kNumHeadings, 1);
    if (costs.traffic > 0) add_traffic_cost(costs.traffic);
    if (costs.lane > 0) add_lane_cost(grid, costs.lane, costs.lane_style);
    if (costs.open > 0) add_open_cost(grid, costs.open);
    if (max_cost == 1) cost.clear();  // e.g. lanes on a map without aisles: plain BFS rows
  }
  if (model == ActionModel::kRotation) {
    faced.resize(size_t(num_free) * kNumHeadings);
    for (int32_t s = 0; s < num_free; ++s)
      for (Heading h = 0; h < kNumHeadings; ++h) {
        const Cell n = forward_cell(grid, free[s], h);
        faced[size_t(s) * kNumHeadings + h] = n == kNoCell ? num_free : slot_of[n];
      }
  }
}

// Traffic cost (see the header): the flow through a slot is its subtree size in the BFS trees
// of kTrafficRoots roots spread over the free cells (a fixed stream: the map alone decides), i.e.
// how many shortest paths to those roots pass through it. A forward move into the slot costs
// 1 + strength x min(1, flow / the flow at kTrafficPercentile), rounded (from any heading).
void FreeCellIndex::add_traffic_cost(double strength) {
  std::vector<double> flow(num_free, 0.0), sub(num_free);
  std::vector<int32_t> parent(num_free), order;
  order.reserve(num_free);
  for (int r = 0; r < kTrafficRoots; ++r) {
    const int32_t root = static_cast<int32_t>((int64_t(r) * num_free) / kTrafficRoots);
    std::fill(parent.begin(), parent.end(), -2);
    std::fill(sub.begin(), sub.end(), 0.0);
    order.assign(1, root);
    parent[root] = -1;
    for (size_t h = 0; h < order.size(); ++h)
      for (int32_t k = adj_begin[order[h]]; k < adj_begin[order[h] + 1]; ++k)
        if (parent[adj[k]] == -2) parent[adj[k]] = order[h], order.push_back(adj[k]);
    for (size_t h = order.size(); h-- > 0;) {
      const int32_t u = order[h];
      sub[u] += 1;
      if (parent[u] >= 0) sub[parent[u]] += sub[u];
      flow[u] += sub[u];
    }
  }
  std::vector<double> sorted(flow);
  const size_t at = static_cast<size_t>(kTrafficPercentile * (sorted.size() - 1));
  std::nth_element(sorted.begin(), sorted.begin() + at, sorted.end());
  const double top = std::max(1.0, sorted[at]);
  for (int32_t s = 0; s < num_free; ++s)
    for (int h = 0; h < kNumHeadings; ++h) raise_cost(s, h, std::lround(strength * std::min(1.0, flow[s] / top)));
}

// Lane cost (see the header): a forward move against the lane of the cell it enters costs
// `extra` more, rounded.
void FreeCellIndex::add_lane_cost(const Grid& grid, double extra, LaneStyle style) {
  const Lanes lanes = derive_lanes(grid, style);
  for (int32_t s = 0; s < num_free; ++s)
    for (Heading h = 0; h < kNumHeadings; ++h)
      if (lanes.against(grid, cell_of[s], h)) raise_cost(s, h, std::lround(extra));
}

// Open cost (see the header): a forward move along an open area (lanes.hpp) costs `extra` more,
// rounded.
void FreeCellIndex::add_open_cost(const Grid& grid, double extra) {
  const OpenAreas areas = derive_open_areas(grid);
  for (int32_t s = 0; s < num_free; ++s)
    for (Heading h = 0; h < kNumHeadings; ++h)
      if (areas.along(grid, cell_of[s], h)) raise_cost(s, h, std::lround(extra));
}

void FreeCellIndex::raise_cost(int32_t slot, int heading, long extra) {
  uint8_t& c = cost[size_t(slot) * kNumHeadings + heading];
  c = static_cast<uint8_t>(std::min<long>(c + extra, UINT8_MAX));
  max_cost = std::max<int32_t>(max_cost, c);
}

size_t FreeCellIndex::bytes() const {
  return sizeof(*this) + slot_of.capacity() * sizeof(int32_t) + cell_of.capacity() * sizeof(Cell) +
         adj_begin.capacity() * sizeof(int32_t) + adj.capacity() * sizeof(int32_t) + blocked.capacity() +
         faced.capacity() * sizeof(int32_t) + cost.capacity();
}

namespace {
std::vector<Cell> blocked_list(const Grid& grid, const std::vector<uint8_t>* blocked) {
  std::vector<Cell> out;
  if (blocked)
    for (Cell c = 0; c < grid.num_cells() && c < Cell(blocked->size()); ++c)
      if ((*blocked)[c]) out.push_back(c);
  return out;
}

// BFS over slots from `goal_slot`, writing distances into d (num_free + 1 entries, all set to
// `unreached` beforehand). The queue is the caller's scratch (reused per thread).
template <typename T>
void bfs_slots(const FreeCellIndex& ix, int32_t goal_slot, T* d, T unreached, std::vector<int32_t>& queue) {
  queue.resize(ix.num_free);
  const int32_t* begin = ix.adj_begin.data();
  const int32_t* adj = ix.adj.data();
  const uint8_t* blocked = ix.blocked.empty() ? nullptr : ix.blocked.data();
  size_t head = 0, tail = 0;
  d[goal_slot] = 0;
  queue[tail++] = goal_slot;
  while (head < tail) {
    const int32_t s = queue[head++];
    const T nd = static_cast<T>(d[s] + 1);
    for (int32_t k = begin[s], e = begin[s + 1]; k < e; ++k) {
      const int32_t n = adj[k];
      if (d[n] != unreached || (blocked && blocked[n])) continue;
      d[n] = nd;
      queue[tail++] = n;
    }
  }
}
}  // namespace

DistRow::DistRow(std::shared_ptr<const FreeCellIndex> index, Cell goal)
    : index_(std::move(index)), slot_of_(index_->slot_of.data()), goal_(goal), narrow_(!index_->wide()) {
  bfs();
}

DistRow::DistRow(const Grid& grid, Cell goal, const std::vector<uint8_t>* blocked)
    : DistRow(std::make_shared<const FreeCellIndex>(grid, blocked_list(grid, blocked)), goal) {}

void DistRow::bfs() {
  const FreeCellIndex& ix = *index_;
  const int32_t goal_slot = ix.slot_of.at(goal_);
  if (goal_slot >= ix.num_free) throw std::out_of_range("distance row: goal is not a free cell");
  if (ix.model == ActionModel::kRotation) return bfs_rotation(goal_slot);
  thread_local std::vector<int32_t> queue;
  if (narrow_) {
    d16_.assign(size_t(ix.num_free) + 1, 0xFFFF);
    bfs_slots<uint16_t>(ix, goal_slot, d16_.data(), 0xFFFF, queue);
  } else {
    d32_.assign(size_t(ix.num_free) + 1, UINT32_MAX);
    bfs_slots<uint32_t>(ix, goal_slot, d32_.data(), UINT32_MAX, queue);
  }
}

// Reverse BFS over states s * 4 + h from the goal's four headings. The predecessors of (s, h)
// are (s, h rotated either way), one rotation away, and the state behind s facing h, one forward
// move away. Blocked slots are never entered. Then per slot: the least distance and the excess
// of each heading over it.
void DistRow::bfs_rotation(int32_t goal_slot) {
  const int32_t f = index_->num_free;
  thread_local std::vector<uint32_t> d;
  d.assign(size_t(f) * kNumHeadings, UINT32_MAX);
  if (index_->cost.empty()) unit_rotation(goal_slot, d);
  else weighted_rotation(goal_slot, d);
  if (!narrow_) {  // the index's bound is loose with step costs: 16 bits do if the distances fit
    uint32_t most = 0;
    for (uint32_t v : d)
      if (v != UINT32_MAX) most = std::max(most, v);
    narrow_ = most < 0xFFFF;
  }
  if (narrow_) {
    packed_.assign(3 * (size_t(f) + 1), 0);
    for (size_t k = 0; k < packed_.size(); k += 3) packed_[k] = packed_[k + 1] = 0xFF;
  } else {
    d32_.assign(size_t(f) + 1, UINT32_MAX);
    excess_.assign(size_t(f) + 1, 0);
  }
  for (int32_t s = 0; s < f; ++s) {
    const uint32_t* ds = &d[size_t(s) * 4];
    const uint32_t least = std::min(std::min(ds[0], ds[1]), std::min(ds[2], ds[3]));
    if (least == UINT32_MAX) continue;
    uint8_t bits = 0;
    for (int h = 0; h < kNumHeadings; ++h) bits |= static_cast<uint8_t>((ds[h] - least) << (2 * h));
    if (narrow_) {
      const uint16_t v = static_cast<uint16_t>(least);
      std::memcpy(&packed_[3 * size_t(s)], &v, sizeof v);
      packed_[3 * size_t(s) + 2] = bits;
    } else {
      d32_[s] = least;
      excess_[s] = bits;
    }
  }
}

// The reverse BFS: every action costs 1.
void DistRow::unit_rotation(int32_t goal_slot, std::vector<uint32_t>& d) {
  const FreeCellIndex& ix = *index_;
  const int32_t f = ix.num_free;
  thread_local std::vector<int32_t> queue;
  queue.resize(size_t(f) * kNumHeadings);
  const int32_t* faced = ix.faced.data();
  const uint8_t* blocked = ix.blocked.empty() ? nullptr : ix.blocked.data();
  size_t head = 0, tail = 0;
  for (int h = 0; h < kNumHeadings; ++h) d[goal_slot * 4 + h] = 0, queue[tail++] = goal_slot * 4 + h;
  auto visit = [&](int32_t st, uint32_t nd) {
    if (d[st] == UINT32_MAX) d[st] = nd, queue[tail++] = st;
  };
  while (head < tail) {
    const int32_t st = queue[head++], s = st >> 2, h = st & 3;
    const uint32_t nd = d[st] + 1;
    visit(s * 4 + ((h + 1) & 3), nd);
    visit(s * 4 + ((h + 3) & 3), nd);
    const int32_t behind = faced[size_t(s) * 4 + ((h + 2) & 3)];
    if (behind < f && !(blocked && blocked[behind])) visit(behind * 4 + h, nd);
  }
}

// With step costs, Dial's algorithm: a forward move into slot s in heading h costs
// ix.cost[4 s + h], a turn 1.
void DistRow::weighted_rotation(int32_t goal_slot, std::vector<uint32_t>& d) {
  const FreeCellIndex& ix = *index_;
  const int32_t f = ix.num_free;
  const int32_t* faced = ix.faced.data();
  const uint8_t* blocked = ix.blocked.empty() ? nullptr : ix.blocked.data();
  const uint32_t buckets = static_cast<uint32_t>(ix.max_cost) + 1;  // Dial: distances span at most this many
  thread_local std::vector<std::vector<int32_t>> bucket;
  bucket.resize(buckets);
  for (auto& b : bucket) b.clear();
  for (int h = 0; h < kNumHeadings; ++h) d[goal_slot * 4 + h] = 0, bucket[0].push_back(goal_slot * 4 + h);
  size_t pending = 4;
  for (uint32_t dist = 0; pending > 0; ++dist) {
    auto& b = bucket[dist % buckets];
    for (size_t k = 0; k < b.size(); ++k) {
      const int32_t st = b[k];
      --pending;
      if (d[st] != dist) continue;
      const int32_t s = st >> 2, h = st & 3;
      auto relax = [&](int32_t to, uint32_t nd) {
        if (nd < d[to]) d[to] = nd, bucket[nd % buckets].push_back(to), ++pending;
      };
      relax(s * 4 + ((h + 1) & 3), dist + 1);
      relax(s * 4 + ((h + 3) & 3), dist + 1);
      const int32_t behind = faced[size_t(s) * 4 + ((h + 2) & 3)];
      if (behind < f && !(blocked && blocked[behind])) relax(behind * 4 + h, dist + ix.cost[size_t(s) * 4 + h]);
    }
    b.clear();
  }
}

size_t DistRow::bytes() const {
  return sizeof(DistRow) + d16_.capacity() * sizeof(uint16_t) + d32_.capacity() * sizeof(uint32_t) +
         excess_.capacity() + packed_.capacity();
}

DistTable::DistTable(const Grid& grid, size_t budget_bytes)
    : DistTable(grid, std::vector<Cell>{}, budget_bytes) {}

namespace {
std::atomic<uint64_t> next_table_id{1};
}  // namespace

DistTable::DistTable(const Grid& grid, const std::vector<Cell>& blocked, size_t budget_bytes)
    : DistTable(grid, blocked, ActionModel::kMapf, budget_bytes) {}

DistTable::DistTable(const Grid& grid, ActionModel model, size_t budget_bytes)
    : DistTable(grid, std::vector<Cell>{}, model, budget_bytes) {}

DistTable::DistTable(const Grid& grid, const std::vector<Cell>& blocked, ActionModel model, size_t budget_bytes)
    : DistTable(grid, blocked, model, budget_bytes, StepCosts{}) {}

DistTable::DistTable(const Grid& grid, ActionModel model, size_t budget_bytes, StepCosts costs)
    : DistTable(grid, std::vector<Cell>{}, model, budget_bytes, costs) {}

DistTable::DistTable(const Grid& grid, const std::vector<Cell>& blocked, ActionModel model, size_t budget_bytes,
                     StepCosts costs)
    : grid_(grid),
      index_(std::make_shared<const FreeCellIndex>(grid, blocked, model, costs)),
      costs_(costs),
      id_(next_table_id++),
      budget_(budget_bytes) {}

size_t DistTable::row_bytes() const {
  const size_t excess = index_->model == ActionModel::kRotation ? 1 : 0;
  return sizeof(DistRow) + (size_t(index_->num_free) + 1) * ((index_->wide() ? 4 : 2) + excess) + kEntryOverhead;
}

void DistTable::check_goal(Cell goal) const {
  if (!grid_.is_free(goal))
    throw std::out_of_range("distance table: goal " + grid_.describe(goal) + " is not a free cell");
}

std::shared_ptr<const DistRow> DistTable::row(Cell goal) const {
  check_goal(goal);
  const uint64_t now = ++clock_;
  {
    std::shared_lock lock(mutex_);
    auto it = rows_.find(goal);
    if (it != rows_.end()) {
      it->second->last_use.store(now, std::memory_order_relaxed);
      return it->second->row;
    }
  }
  // BFS outside the lock: two threads may race to compute the same row; one copy wins.
  auto fresh = std::make_shared<const DistRow>(index_, goal);
  ++bfs_count_;
  std::unique_lock lock(mutex_);
  return insert_locked(std::move(fresh), now);
}

std::shared_ptr<const DistRow> DistTable::insert_locked(std::shared_ptr<const DistRow> fresh, uint64_t now) const {
  auto [it, inserted] = rows_.try_emplace(fresh->goal());
  if (inserted) {
    it->second = std::make_unique<Entry>();
    it->second->row = std::move(fresh);
    bytes_ += it->second->row->bytes() + kEntryOverhead;
  }
  it->second->last_use.store(now, std::memory_order_relaxed);
  auto result = it->second->row;
  if (bytes_ > budget_ && bytes_ > evict_at_) evict_locked();
  peak_bytes_ = std::max(peak_bytes_, bytes_);
  return result;
}

void DistTable::evict_locked() const {
  // Drop the least recently used rows nobody else holds until a quarter of the budget is free,
  // so the O(n log n) sort is amortised over many insertions. A row a solver still holds is
  // kept: evicting it would free nothing and only cost a second BFS.
  std::vector<std::pair<uint64_t, Cell>> order;
  order.reserve(rows_.size());
  for (auto& [goal, e] : rows_)
    if (e->row.use_count() == 1) order.emplace_back(e->last_use.load(std::memory_order_relaxed), goal);
  std::sort(order.begin(), order.end());
  const size_t target = budget_ - budget_ / 4;
  for (auto& [use, goal] : order) {
    if (bytes_ <= target) break;
    auto it = rows_.find(goal);
    bytes_ -= it->second->row->bytes() + kEntryOverhead;
    rows_.erase(it);
    ++evictions_;
  }
  if (bytes_ > budget_) {
    // Held rows alone exceed the budget: try again only after another sixteenth of it.
    ++over_budget_;
    evict_at_ = bytes_ + std::max<size_t>(budget_ / 16, row_bytes());
  } else {
    evict_at_ = 0;
  }
}

void DistTable::prefetch(const std::vector<Cell>& goals) const {
  // The distinct free goals not cached yet, in first-seen order.
  std::vector<Cell> missing;
  {
    std::shared_lock lock(mutex_);
    std::unordered_map<Cell, char> seen;
    seen.reserve(goals.size());
    for (Cell g : goals) {
      if (!grid_.is_free(g) || !seen.emplace(g, 1).second) continue;
      auto it = rows_.find(g);
      if (it == rows_.end()) missing.push_back(g);
    }
  }
  if (missing.empty()) return;
  std::vector<std::shared_ptr<const DistRow>> fresh(missing.size());
  int sync = 0;
  GDRHCR_TSAN_RELEASE(&sync);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, missing.size(), 1), [&](const tbb::blocked_range<size_t>& r) {
    GDRHCR_TSAN_ACQUIRE(&sync);
    for (size_t k = r.begin(); k < r.end(); ++k) fresh[k] = std::make_shared<const DistRow>(index_, missing[k]);
    GDRHCR_TSAN_RELEASE(&sync);
  });
  GDRHCR_TSAN_ACQUIRE(&sync);
  bfs_count_ += missing.size();
  std::unique_lock lock(mutex_);
  for (auto& f : fresh) insert_locked(std::move(f), ++clock_);
}

DistTable::AllRows DistTable::prefetch_all(std::chrono::steady_clock::time_point deadline) const {
  AllRows all;
  const auto& cells = grid_.free_cells();
  if (cells.empty()) return all;
  const size_t before = cached_bytes();
  row(cells[0]);
  const size_t one = cached_bytes() - before;
  all.bytes = cells.size() * (one > 0 ? one : row_bytes());
  all.fit = all.bytes <= budget_;
  if (!all.fit) return all;
  constexpr size_t kBatch = 256;  // rows per parallel batch, between looks at the deadline
  size_t done = 0;
  while (done < cells.size() && std::chrono::steady_clock::now() < deadline) {
    const size_t end = std::min(cells.size(), done + kBatch);
    prefetch(std::vector<Cell>(cells.begin() + done, cells.begin() + end));
    done = end;
  }
  all.computed = std::max<size_t>(done, 1);
  return all;
}

std::vector<std::shared_ptr<const DistRow>> DistTable::rows(const std::vector<Cell>& goals) const {
  for (Cell g : goals) check_goal(g);
  prefetch(goals);
  std::vector<std::shared_ptr<const DistRow>> out;
  out.reserve(goals.size());
  for (Cell g : goals) out.push_back(row(g));  // cached now, unless evicted meanwhile
  return out;
}

bool DistTable::has(Cell goal) const {
  std::shared_lock lock(mutex_);
  return rows_.count(goal) > 0;
}

size_t DistTable::cached_rows() const {
  std::shared_lock lock(mutex_);
  return rows_.size();
}

size_t DistTable::cached_bytes() const {
  std::shared_lock lock(mutex_);
  return bytes_;
}

size_t DistTable::peak_bytes() const {
  std::shared_lock lock(mutex_);
  return peak_bytes_;
}

}  // namespace gdrhcr
