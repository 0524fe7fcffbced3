// Shortest-path distance tables, one per goal, computed by BFS on first use and cached.
//
// As in Kei18/pibt2 and lacam3 (Okumura et al.), every solver shares one table, so a goal's BFS
// is paid once however many agents and solvers ask. Unlike RHCR's all-pairs table (437 MB on
// warehouse-10-20-10-2-1), only goals in use are kept, under a memory budget.
//
// Compact rows (issue 12, fleets of 10,000 robots): a row stores one distance per FREE cell,
// not per grid cell, in 16 bits (0xFFFF = unreachable) when the map has at most 65,534 free
// cells (so every distance fits below the sentinel), else in 32 bits. Grid cells are mapped to
// free-cell slots by one index shared by all rows; obstacles map to an extra slot that always
// reads unreachable. On warehouse-20-40-10-2-2 (164 x 340, 38,756 free cells) a row is 77.5 KB
// instead of the 223 KB of an int32 array over the grid.
//
// Memory: every row handed out is owned by the cache until evicted, and only rows nobody else
// holds (shared_ptr use count 1) are evicted, least recently used first. So cached_bytes() is
// the memory of every live row (exact: payload plus object sizes), and it stays within the
// budget unless the rows solvers hold at once exceed it (counted by over_budget_inserts()).
//
// Batch warm-up: prefetch(goals) computes the missing rows of a set of goals in parallel on
// oneTBB's pool (one BFS per task); rows(goals) does the same and returns the handles.
//
// Turns (issue 23): in the rotation action model (action_model.hpp) a row holds the distance to
// the goal from every (cell, heading) state, counting quarter turns as steps: a reverse BFS over
// 4 states per free cell from the goal's four headings (any heading reaches a goal). The row
// stays compact: per free cell the least distance over its headings, as in a plain row, plus one
// byte holding, per heading, its excess over that least distance in 2 bits (a turn costs at most
// 2 steps, so the excess is 0, 1 or 2). row[c] reads the least distance over c's headings,
// row.at(c, h) the distance from heading h; in the mapf model both read the cell distance. A row
// whose distances fit in 16 bits keeps the two side by side, 3 bytes a cell, so a read of
// row.at(c, h) touches one cache line (PIBT over 10,000 agents is bound by these reads).
// With step costs (below) the bound on a distance grows with the largest cost, so the index may
// call for 32 bits; a row whose own distances fit in 16 bits is stored in 16 all the same
// (Paris_1_256 with traffic costs: 142 KB a row instead of 236 KB).
//
// Step costs (issue 24, congestion; rotation model only; off unless asked for). A forward move
// may cost more than 1, so rows are computed by Dial's algorithm; a turn still costs 1, so the
// excess bits hold. Two costs add up:
//   - traffic cost (after the traffic-flow costs of Chen et al., AAAI 2024): a move into a cell
//     costs more by how many shortest paths pass through the cell (a sampled betweenness), so
//     rows lead around the map's busiest cells when the detour is short, and traffic that would
//     all cross the middle of a city spreads out;
//   - lane cost: a move against the direction of the one-way lane it is in (lanes.hpp, derived
//     from the map's aisles) costs more, so rows send traffic one way along each aisle;
//   - open cost: a move along an open area of a map with aisles (lanes.hpp; a warehouse's band
//     before its stations) costs more, so rows travel the map's length in the aisles and cross
//     the open areas.

// Thread-safe: parallel groups query it at once. Two threads asking for the same missing row at
// the same moment may both run its BFS (counted); one copy is kept.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <unordered_map>
#include <vector>

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/grid.hpp"
#include "gdrhcr/huge_pages.hpp"
#include "gdrhcr/lanes.hpp"


namespace gdrhcr {

constexpr int kUnreachable = INT32_MAX / 4;

// Extra costs of forward moves in the rotation model (see the file comment); 0 = none.
struct StepCosts {
  double traffic = 0;  // up to this much more into the busiest cells
  double lane = 0;     // this much more against a lane's direction
  LaneStyle lane_style = LaneStyle::kAisles;  // which lines the lanes are (lanes.hpp)
  double open = 0;     // this much more along an open area
  bool any() const { return traffic > 0 || lane > 0 || open > 0; }
};

// The free cells of a grid as dense slots 0..F-1 (in increasing cell order), the neighbour lists
// in slot space, and the cell -> slot map (obstacles -> F). Built once per DistTable and shared
// by its rows, so a row outliving its table stays readable.
struct FreeCellIndex {
  explicit FreeCellIndex(const Grid& grid, const std::vector<Cell>& blocked = {},
                         ActionModel model = ActionModel::kMapf, StepCosts costs = {});
  ActionModel model = ActionModel::kMapf;
  int32_t num_free = 0;
  std::vector<int32_t> slot_of;       // per grid cell; num_free for obstacles
  std::vector<Cell> cell_of;          // per slot
  std::vector<int32_t> adj_begin;     // CSR over slots: neighbours of s are
  std::vector<int32_t> adj;           //   adj[adj_begin[s] .. adj_begin[s+1])
  std::vector<uint8_t> blocked;       // per slot; empty when nothing is blocked
  std::vector<int32_t> faced;         // rotation: 4 per slot, the slot heading h faces, or num_free
  std::vector<uint8_t> cost;          // rotation with step costs: per slot s and heading h (4 s + h),
                                      //   a forward move into s in heading h; else empty
  int32_t max_cost = 1;               // the largest step cost
  static constexpr int kTrafficRoots = 64;
  static constexpr double kTrafficPercentile = 0.99;
  void add_traffic_cost(double strength);
  void add_lane_cost(const Grid& grid, double extra, LaneStyle style);
  void add_open_cost(const Grid& grid, double extra);
  void raise_cost(int32_t slot, int heading, long extra);
  // A shortest path over (cell, heading) states makes at most F - 1 moves, at most one turn
  // between two moves and two before the first, so its length is below 2F: rotation rows are
  // 16 bits up to half as many free cells.
  bool wide() const {
    return model == ActionModel::kRotation ? int64_t(num_free) * (max_cost + 1) > kMaxNarrowFree
                                           : num_free > kMaxNarrowFree;
  }
  size_t bytes() const;
  // 16-bit rows hold distances 0..65,534 and 0xFFFF as the sentinel; a component of F free
  // cells has distances up to F - 1, so F <= 65,535 fits. We keep one spare: F <= 65,534.
  static constexpr int32_t kMaxNarrowFree = 65534;
};

// Distances from every cell to one goal (kUnreachable for obstacles and other components).
class DistRow {
 public:
  // A full BFS from `goal` over `index` (whose blocked slots the BFS never enters, though it
  // may start from one).
  DistRow(std::shared_ptr<const FreeCellIndex> index, Cell goal);
  // The same for a one-off row; builds its own index (tests, small tools).
  DistRow(const Grid& grid, Cell goal, const std::vector<uint8_t>* blocked = nullptr);

  // The distance from cell c (in the rotation model: from its best heading).
  int operator[](Cell c) const {
    const int32_t s = slot_of_[c];
    if (!packed_.empty()) return packed_distance(packed_.data() + 3 * size_t(s));
    if (narrow_) {
      const uint16_t v = d16_[s];
      return v == 0xFFFF ? kUnreachable : int(v);
    }
    const uint32_t v = d32_[s];
    return v == UINT32_MAX ? kUnreachable : int(v);
  }
  // The distance from cell c facing h, turns counted in the rotation model (mapf: row[c]).
  int at(Cell c, Heading h) const {
    if (!packed_.empty()) {
      const uint8_t* p = packed_.data() + 3 * size_t(slot_of_[c]);
      const int d = packed_distance(p);
      return d >= kUnreachable ? d : d + ((p[2] >> (2 * h)) & 3);
    }
    const int d = (*this)[c];
    if (excess_.empty() || d >= kUnreachable) return d;
    return d + ((excess_[slot_of_[c]] >> (2 * h)) & 3);
  }
  // Asks the processor to fetch what at(c, h) reads, ahead of the read (a row is one of thousands:
  // its entries are rarely in cache, and a loop over many agents can overlap their misses).
  void prefetch(Cell c) const {
    const int32_t s = slot_of_[c];
    if (!packed_.empty()) return __builtin_prefetch(packed_.data() + 3 * size_t(s));
    if (narrow_) __builtin_prefetch(d16_.data() + s);
    else __builtin_prefetch(d32_.data() + s);
    if (!excess_.empty()) __builtin_prefetch(excess_.data() + s);
  }
  Cell goal() const { return goal_; }
  bool narrow() const { return narrow_; }
  ActionModel action_model() const { return index_->model; }
  // Heap and object bytes of this row (the shared index is counted once, by the table).
  size_t bytes() const;

 private:
  void bfs();
  void bfs_rotation(int32_t goal_slot);
  // Distances to the goal per state (slot * 4 + heading) into d (all UINT32_MAX beforehand).
  void unit_rotation(int32_t goal_slot, std::vector<uint32_t>& d);
  void weighted_rotation(int32_t goal_slot, std::vector<uint32_t>& d);
  std::shared_ptr<const FreeCellIndex> index_;
  const int32_t* slot_of_;
  Cell goal_;
  bool narrow_;
  static int packed_distance(const uint8_t* p) {
    uint16_t v;
    std::memcpy(&v, p, sizeof v);
    return v == 0xFFFF ? kUnreachable : int(v);
  }
  std::vector<uint16_t, HugePageAllocator<uint16_t>> d16_;  // num_free + 1 slots, the last one unreachable (obstacles)
  std::vector<uint32_t, HugePageAllocator<uint32_t>> d32_;  // the same, for maps with more than 65,534 free cells
  std::vector<uint8_t, HugePageAllocator<uint8_t>> excess_;  // rotation, with d32_: per slot, 2 bits per heading over the least distance
  // Rotation, distances under 0xFFFF: per slot 3 bytes, the least distance (16 bits, as d16_) and
  // then the excess byte, so that one cache line holds both (the same bytes as d16_ and excess_).
  std::vector<uint8_t, HugePageAllocator<uint8_t>> packed_;
};

class DistTable {
 public:
  static constexpr size_t kDefaultBudgetBytes = size_t(256) << 20;
  explicit DistTable(const Grid& grid, size_t budget_bytes = kDefaultBudgetBytes);
  // Distances that route around `blocked` free cells, e.g. robots that went offline and now
  // stand where they stopped: paths avoid them, and a goal on one is still accepted (the
  // offline robot's own), but no other cell reaches it.
  DistTable(const Grid& grid, const std::vector<Cell>& blocked, size_t budget_bytes = kDefaultBudgetBytes);
  // The same in an action model: kRotation rows count turns (see above).
  DistTable(const Grid& grid, ActionModel model, size_t budget_bytes = kDefaultBudgetBytes);
  DistTable(const Grid& grid, const std::vector<Cell>& blocked, ActionModel model,
            size_t budget_bytes = kDefaultBudgetBytes);
  // Rotation rows with step costs: see the file comment.
  DistTable(const Grid& grid, ActionModel model, size_t budget_bytes, StepCosts costs);
  DistTable(const Grid& grid, const std::vector<Cell>& blocked, ActionModel model, size_t budget_bytes,
            StepCosts costs);

  // The row for `goal`, computing it on first use. Throws std::out_of_range for a blocked goal.
  std::shared_ptr<const DistRow> row(Cell goal) const;
  int get(Cell goal, Cell from) const { return (*row(goal))[from]; }
  int get(Cell goal, Cell from, Heading h) const { return row(goal)->at(from, h); }
  ActionModel action_model() const { return index_->model; }
  const StepCosts& step_costs() const { return costs_; }
  // What the rows charge for a forward move into free cell c in heading h: 1 without step costs.
  int forward_cost(Cell c, Heading h) const {
    if (index_->cost.empty()) return 1;
    return index_->cost[size_t(index_->slot_of[c]) * kNumHeadings + h];
  }

  // Computes the missing rows among `goals` in parallel (oneTBB), as a batch warm-up. Goals
  // that are not free cells are skipped. Rows are inserted as if queried in the given order.
  void prefetch(const std::vector<Cell>& goals) const;
  // Every free cell's row, when all of them fit in the budget (measured on one row as
  // computed: see narrow rows above), in parallel batches until `deadline`: with them at hand
  // no later step waits for a row, whatever goals come. Returns the rows computed; nothing is
  // computed when they do not fit (but the one row measured).
  struct AllRows {
    bool fit = false;     // every row fits in the budget
    size_t bytes = 0;     // their bytes, by the measured row
    size_t computed = 0;  // rows computed before the deadline (all of them when it did not come)
  };
  AllRows prefetch_all(std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max()) const;
  // The rows of `goals` (same order), missing ones computed in parallel. Throws like row().
  std::vector<std::shared_ptr<const DistRow>> rows(const std::vector<Cell>& goals) const;

  const Grid& grid() const { return grid_; }
  // Unique per table in this process: a solver that keeps rows across calls knows whether they
  // came from this table (a new table may reuse an old one's address).
  uint64_t id() const { return id_; }
  size_t budget_bytes() const { return budget_; }
  size_t cached_rows() const;
  // Whether the row of `goal` is cached now, so that row(goal) costs no BFS (until an eviction).
  // Does not count as a use of the row.
  bool has(Cell goal) const;
  // Bytes of the cached rows (every live row the table handed out), exact.
  size_t cached_bytes() const;
  size_t peak_bytes() const;
  // Bytes of the shared free-cell index (paid once per table).
  size_t index_bytes() const { return index_->bytes(); }
  size_t row_bytes() const;  // bytes of one row on this map (at most: see narrow rows above)
  uint64_t bfs_count() const { return bfs_count_.load(); }
  uint64_t evictions() const { return evictions_.load(); }
  // Insertions that left the cache over budget because every cached row was held by a solver.
  uint64_t over_budget_inserts() const { return over_budget_.load(); }

 private:
  struct Entry {
    std::shared_ptr<const DistRow> row;
    mutable std::atomic<uint64_t> last_use{0};
  };
  std::shared_ptr<const DistRow> insert_locked(std::shared_ptr<const DistRow> fresh, uint64_t now) const;
  void evict_locked() const;
  void check_goal(Cell goal) const;

  const Grid& grid_;
  std::shared_ptr<const FreeCellIndex> index_;
  StepCosts costs_;
  uint64_t id_;
  size_t budget_;
  mutable std::shared_mutex mutex_;
  mutable std::unordered_map<Cell, std::unique_ptr<Entry>> rows_;
  mutable size_t bytes_ = 0, peak_bytes_ = 0;
  mutable size_t evict_at_ = 0;  // bytes above which the next insertion tries to evict
  mutable std::atomic<uint64_t> clock_{0};
  mutable std::atomic<uint64_t> bfs_count_{0};
  mutable std::atomic<uint64_t> evictions_{0};
  mutable std::atomic<uint64_t> over_budget_{0};
};

}  // namespace gdrhcr
