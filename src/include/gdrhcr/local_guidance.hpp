// Local guidance: short spatio-temporal paths planned with collision costs, which PIBT follows.
// Idea after Arita & Okumura, "Lifelong LaCAM with Local Guidance" (SoCS 2026): every agent
// gets a path over the next W timesteps from a space-time A* whose cost is time plus a penalty
// for every step that runs into another agent's guidance path (a vertex or a swap), and whose
// heuristic is the shortest-path distance to the goal. PIBT then tries each agent's next
// guidance cell first, so agents spread over parallel aisles and queue instead of meeting
// head-on, while PIBT keeps the step collision-free.
//
// A step pays the collision cost for meeting a path at its cell (vertex) and again for swapping
// with one (cost_per_kind): stepping into a cell another agent will hold while a third comes the
// other way is two conflicts to resolve, and guidance that counts it once leads agents into
// oncoming streams.
//
// Contraflow (traffic-aware guidance, after Chen, Harabor, Li, Stuckey, "Traffic Flow
// Optimisation for Lifelong Multi-Agent Path Finding", AAAI 2024): a step along an edge also
// pays a small cost per guidance path that goes the other way along it anywhere in the window,
// not only at the same time. Agents then pick lanes, aisles and doors that others use in their
// own direction, and streams stop meeting head-on.
//
// Conflicts `near_steps` or more steps ahead may cost less (far_collision_cost): the further
// ahead, the less the others' paths foretell. The defaults of all these costs, and the figures
// behind them, are in the parameter table (planner_params.cpp) and docs/results.md.
//
// A search ends at the window's end or on the goal (the agent gets its next goal there).
// Guidance paths are kept across steps in absolute time and replanned lazily: when the agent is
// not where its path says, when its goal changed, or when less than half the window is left.
// The collision table counts, per (time mod (W+1), cell), the guidance paths there and, per
// direction, those leaving the cell, so adding, removing and querying a path is O(W).
//
// Cells the world blocks for a while (WorldView::blocked: a late robot still leaving them)
// count as taken in every search for `blocked_steps` steps, so guidance goes around them when a
// detour is cheaper than the wait.
//
// Refinement, the anytime part (after the repair loop of MAPF-LNS2, Li, Chen, Harabor, Stuckey,
// Koenig, AAAI 2022, with single agents as neighbourhoods): after the update, passes over the
// agents in the same order search again every path that still meets another, now seeing every
// other path, until a pass finds none, the passes run out or the deadline comes. Each search is
// a best response to the others, so collisions left by the first pass (an early agent did not
// see the later ones) are planned around. With a step budget the passes fill the guidance's
// share of it.
//
// Parallel update (fleets of thousands): with `phases` P >= 2 the map is cut into
// bands across its longer side, each ceil(2W / (P - 1)) cells wide, and band b is updated in
// phase b mod P. After stale paths are dropped every path starts at its agent's cell, so a
// search, its path and the path it replaces stay within W cells of the agent: two bands of one
// phase never touch the same cell and are updated concurrently (oneTBB, the caller's arena).
// Within a band agents go in the given order; a later phase sees the earlier phases' new paths.
// Each band draws its random numbers from (seed, timestep, band), so results do not depend on
// the number of threads.
#pragma once

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "gdrhcr/open_list.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr {

struct LocalGuidanceConfig {
  int window = 20;               // W: timesteps each guidance path covers
  double collision_cost = 3.0;   // added per kind of conflict (vertex, swap) a step meets
  // true: a step that meets one path at its cell and another swapping with it pays the cost
  // twice (once per kind of conflict); false: once, whatever it meets.
  bool cost_per_kind = true;
  // Conflicts `near_steps` or more steps ahead of the search's start cost `far_collision_cost`
  // instead (< 0: collision_cost): the further ahead, the less the others' paths foretell.
  double far_collision_cost = -1;
  int near_steps = 3;
  // Traffic: a step along an edge pays this per guidance path planned the other way along it at
  // any time in the window (contraflow), so streams through a door or an aisle keep one
  // direction instead of meeting head-on later (0 = none).
  double contraflow_cost = 0;
  // Mapf model: among equally cheap paths, the one with the fewest changes of direction (a tie
  // break, kStraightTieBreak per change), for robots that turn before a move into a cell they do
  // not face (fleet_sim's and real robots under the ROS node).
  bool straight = false;
  // false: replan every agent every step; true: keep paths until they are left, the goal
  // changes, they meet another path or less than `keep` steps are left (cheaper).
  bool lazy = false;
  int max_expansions = 4000;    // per search; past it the deepest cheapest node so far is used
  int keep = -1;                 // a kept path must still cover this many steps (-1: window / 2)
  uint64_t seed = 1;             // random order of neighbours in the search
  int recheck = 20;              // a kept path is replanned if it meets another path within this many steps
  int phases = 0;                // 0: one sequential pass; P >= 2: banded parallel update (above)
  // WorldView::blocked cells count as taken for this many steps from now (-1: the window).
  int blocked_steps = -1;
  // Refinement passes after the update (the anytime part): each searches again every path that
  // meets another, until none does or the update's deadline comes. -1: kAnytimePasses when the
  // update has a deadline (a step budget), none without.
  int refine = -1;
  static constexpr int kAnytimePasses = 3;
  // lg-straight: the cost of a change of direction, below the 1e-3 per path met that prefers the
  // less crowded of equally cheap steps.
  static constexpr float kStraightTieBreak = 1e-4f;
};

class LocalGuidance {
 public:
  LocalGuidance(const Grid& grid, int num_agents, LocalGuidanceConfig config);
  ~LocalGuidance();

  // Brings the guidance of `agents` up to date for timestep world.timestep, in the given order
  // (earlier agents' paths are seen by later ones). Paths of other agents stay in the table.
  // With a deadline, agents not reached by then keep no guidance this step (counted). The
  // refinement passes stop at the deadline or at `refine_until`, whichever comes first.
  void update(const WorldView& world, const std::vector<int>& agents,
              std::chrono::steady_clock::time_point deadline = std::chrono::steady_clock::time_point::max(),
              std::chrono::steady_clock::time_point refine_until = std::chrono::steady_clock::time_point::max());
  // Sets agent i's expected path from time world.timestep on (e.g. a plan made by another
  // solver), so guidance searches avoid it; path[0] is its cell now. With `goal`, the path is
  // taken as a guidance path planned for that goal (a lazy update may keep it); without, it is
  // replanned whenever guidance is asked for.
  void set_path(int i, int now, const std::vector<Cell>& path, Cell goal = kNoCell);
  // Forgets agent i's path.
  void clear(int i);

  // Agent i's next guidance cell, or kNoCell when it has none for this step.
  Cell next_cell(int i, int now, Cell at) const;
  // Rotation model: the first cell other than `at` on agent i's path within the next
  // kTurnLookahead steps (a path that turns first stays in its cell while it turns), else `at`
  // when the path waits, kNoCell without a path.
  Cell next_move(int i, int now, Cell at) const;
  static constexpr int kTurnLookahead = 3;
  // Agent i's guidance path from `now` on (empty when none).
  std::vector<Cell> path_from(int i, int now) const;

  long searches() const { return counts_.searches; }
  long cut_short() const { return counts_.cut_short; }
  long kept() const { return counts_.kept; }
  long refined() const { return counts_.refined; }  // searches of the refinement passes
  long expansions() const { return counts_.expansions; }
  const LocalGuidanceConfig& config() const { return cfg_; }
  // Width of a band of the parallel update (0 when sequential).
  int band_width() const;

 private:
  struct Node {
    float g, f;
    int32_t t;
    Cell v;
    int32_t parent;
    Heading h;  // rotation model; kNoHeading in mapf
  };
  struct Counts {
    long searches = 0, expansions = 0, cut_short = 0, kept = 0, refined = 0;
    void add(const Counts& o);
  };
  // What one search knows of a (cell, t) pair: whether it reached it (tag = 2 x the search's
  // stamp) or closed it (+ 1), and the best g it saw; entries of earlier searches have older
  // tags. On small maps one entry per (cell, t) of the map (key = cell x slots + t); where that
  // table would pass kDirectMarksBytes, an open-addressing table of the pairs the search reached
  // (a few hundred), which stays in cache: warehouse-10-20-10-2-1, 800 agents, 6% less CPU. The
  // hashed table keeps its keys apart, so that an entry is 8 bytes in both (fewer cache lines).
  struct Mark {
    uint32_t tag;
    float best_g;
  };
  static constexpr size_t kDirectMarksBytes = size_t{1} << 20;
  struct Marks {
    std::vector<Mark> table;
    std::vector<uint32_t> keys;  // hashed: the key of each entry of `table`
    uint32_t stamp = 0, used = 0, bits = 0;
    bool hashed = false;
    void start(size_t pairs);  // a new search over `pairs` (cell, t) pairs
    Mark& find(uint32_t key);  // the pair's entry (unseen: tag < 2 x stamp)
    void grow();
  };
  // One search's scratch: marks, node pool, open list. One per thread in the parallel update.
  struct Search {
    Marks marks;
    std::vector<Node> nodes;
    OpenList open;
  };
  struct Parallel;
  void drop_past(int i, int now);
  void mark_blocked(const WorldView& world, int sign);
  int blocked_steps() const;
  void enroll(int i, int sign);
  bool is_valid(const WorldView& world, int i) const;
  bool keeps(const WorldView& world, int i) const;
  bool meets_another(int i, int horizon) const;
  int refine_passes(std::chrono::steady_clock::time_point deadline) const;
  void refine(const WorldView& world, const std::vector<int>& agents, std::chrono::steady_clock::time_point deadline,
              std::chrono::steady_clock::time_point until, Search& search, std::minstd_rand& rng, Counts& counts);
  void update_in_order(const WorldView& world, const std::vector<int>& agents,
                       std::chrono::steady_clock::time_point deadline, Search& search,
                       std::minstd_rand& rng, Counts& counts);
  void update_banded(const WorldView& world, const std::vector<int>& agents,
                     std::chrono::steady_clock::time_point deadline, std::chrono::steady_clock::time_point refine_until);
  void plan(const WorldView& world, int i, Search& search, std::minstd_rand& rng, Counts& counts);
  int moves(Cell v, Heading h, bool rot, std::minstd_rand& rng, Cell* nb, Heading* nh) const;
  // What a step from -> to in time slot s (into slot s1), `ahead` steps after the search's start,
  // pays for meeting others.
  float collision_penalty(Cell from, Cell to, int s, int s1, int ahead) const;
  int slot(int abs_t) const { return abs_t % slots_; }
  // The direction of a step between neighbours: 0 +x, 1 -x, 2 +y, 3 -y.
  static int dir(Cell from, Cell to) {
    const int d = to - from;
    return d == 1 ? 0 : d == -1 ? 1 : d > 0 ? 2 : 3;
  }

  const Grid& grid_;
  LocalGuidanceConfig cfg_;
  int slots_;
  std::vector<std::vector<Cell>> path_;  // per agent: cells at start_[i], start_[i]+1, ...
  std::vector<int> start_;
  std::vector<Cell> goal_;               // the goal each path was planned for
  // Per (cell, time slot), the slots of one cell side by side (a step's look-ups at t and t+1
  // share a cache line): paths at the cell, and per direction paths leaving it.
  struct Occupancy {
    uint16_t at;
    uint16_t leaving[4];
  };
  std::vector<Occupancy> occ_;
  // Per cell and direction: guidance paths leaving the cell that way at any time (contraflow).
  std::vector<std::array<uint16_t, 4>> flow_;
  float contraflow_;
  uint16_t& at(Cell c, int s) { return occ_[static_cast<size_t>(c) * slots_ + s].at; }
  uint16_t at(Cell c, int s) const { return occ_[static_cast<size_t>(c) * slots_ + s].at; }
  uint16_t& leaving(Cell c, int s, int d) { return occ_[static_cast<size_t>(c) * slots_ + s].leaving[d]; }
  uint16_t leaving(Cell c, int s, int d) const { return occ_[static_cast<size_t>(c) * slots_ + s].leaving[d]; }
  Search search_;         // the sequential update's scratch
  std::minstd_rand rng_;  // the sequential update's random numbers
  std::unique_ptr<Parallel> parallel_;  // per-thread scratch of the banded update
  std::vector<std::vector<int>> band_agents_;
  Counts counts_;
};

}  // namespace gdrhcr
