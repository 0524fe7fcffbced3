// PIBT: Priority Inheritance with Backtracking for lifelong MAPF.
// Okumura, Machida, Défago, Tamura, "Priority Inheritance with Backtracking for Iterative
// Multi-agent Path Finding", Artificial Intelligence 310, 2022 (IJCAI 2019).
// Swap emulation after Okumura, "Engineering LaCAM*: Towards Real-Time, Large-Scale, and
// Near-Optimal Multi-Agent Pathfinding", AAMAS 2024 (section "PIBT with swap").
//
// One timestep at a time: agents decide in priority order; an agent that wants a cell held by an
// undecided agent lends it its priority, and that agent must move away or the request
// backtracks. Priorities rise with the time since an agent last reached a goal, so nobody
// starves. Never produces a vertex or edge collision.
//
// Swap: in a corridor two agents heading for each other's side deadlock under plain PIBT (the
// pusher can only shove the other back). When the cell an agent wants is held by an agent that
// needs to get past it, and a junction where they can pass is reachable, the agent walks away
// from its goal and pulls the other one after it, until they reach the junction and pass.
//
// Rotation model (issue 23, LoRR's MAPF_T; action_model.hpp): PIBT over (cell, heading) states,
// with short operations. Only forward (F) leaves a cell, so an agent that must turn before it can
// move keeps its cell for a step or two, and giving way takes several steps: turn, [turn,] forward.
// After EPIBT (Nagorny et al., LoRR 2024 winner, arXiv 2511.09193), each agent therefore holds an
// operation, a sequence of kOpSteps actions (F, R, C, W; no turn undoing the last one, no turn at
// the end), and the cells it holds at t+1 .. t+kOpSteps are reserved. An agent's operations are
// ordered by the distance with turns (DistRow::at) from the state they end in. Every agent starts
// the step holding what is left of its last step's operation (then a wait), so plans carry on; an
// agent whose carried operation no longer fits waits. Then, nearest its goal first (agents with
// nothing to reach last), each agent is built: it takes its best operation that is free, or that
// meets the cells of one agent of lower priority, which is then built around it in turn
// (recursively, up to kOpVisits builds of an agent a round); a chain that fails is undone and the
// next operation tried. With a deadline the rest of the time rebuilds agents in random order
// (the same rule), keeping each change that does not lower the fleet's score (each agent's gain
// over waiting, weighted by its rank: EPIBT's LNS), until a round gains nothing; with
// search_threads the rounds run in two halves of the map at once (across x and y in turn). Only the first
// action is executed. A call in which more than half of its agents have stood kStallSteps steps
// or more is planned over cells instead: operations do not get out of some jams that cells do
// (rooms' doors). PibtOptions::rotation picks these operations or cells chosen with turns
// counted and executed turning first. The swap applies in this model only to an agent that has
// stood long (rotation_swap_wait): over operations it retreats, its operations that leave its
// cell by another way first, and the agent that must get past it follows.
#pragma once

#include <chrono>
#include <climits>
#include <random>
#include <vector>

#include "gdrhcr/local_guidance.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr {

struct PibtOptions {
  // Reset an agent's priority when it reaches a goal (detected as its goal changing between
  // calls, since the simulator and the node hand out the next goal before the next call).
  bool priority_reset = true;
  bool swap = true;  // LaCAM*'s swap emulation
  // Order among equally near cells: kFreeFirst prefers a cell nobody stands on (fewer pushes),
  // then random; kRandom is random alone (plain PIBT).
  enum class TieBreak { kRandom, kFreeFirst };
  TieBreak tie_break = TieBreak::kFreeFirst;
  // Rotation model: kOperations plans 3-action operations (after EPIBT, above); kCells plans
  // cells as in the mapf model, choosing among them by the distance with turns from the heading
  // the move leaves the agent in plus the quarter turns it needs (after WPPL, Jiang et al., arXiv
  // 2404.16162), then executes the step by turning first: an agent facing its next cell goes
  // forward, one that does not turns towards it and stays, and whoever was to enter a staying
  // agent's cell stays too (rotation_actions_for_step, mapf_in_rotation.hpp). One push per agent,
  // so its time is linear in the agents, as in the mapf model. kAuto plans a call over operations
  // when the time to its deadline (from the caller's step start if given, see set_deadline; else
  // the time left) is kOpRoom times what the first pass over operations takes
  // (so the search has room), else over cells: without a deadline, or at small budgets, operations
  // do worse than cells in packed crowds (docs/results.md, session 36).
  enum class Rotation { kOperations, kCells, kAuto };
  Rotation rotation = Rotation::kOperations;
  static const char* name(Rotation r) { return r == Rotation::kCells ? "cells" : r == Rotation::kAuto ? "auto" : "operations"; }
  // Rotation model: the swap starts only for an agent that has stood in its cell this many steps
  // (0: never), and goes on while its partner still needs it (over operations: it retreats). Used
  // at every step it holds agents back (a retreat costs turns); without it an agent heading into a
  // dead end whose occupant can leave only through its cell waits for ever, and the agents queued
  // behind it.
  int rotation_swap_wait = 0;
  // Rotation model, kCells, a call that moves the whole fleet: the configuration PIBT chose is
  // carried out to the end before PIBT plans again. Agents that face their cell move, the others
  // turn (at most two turns, then forward), and agents already in their cell wait for the rest;
  // after at most three steps every agent stands where PIBT put it. Replanning after every action
  // instead breaks a push chain whenever one of its agents must turn, and wastes the turns of
  // agents that PIBT sends elsewhere next step. It pays only in packed crowds (after WPPL's
  // executor for its densest instances, Jiang et al., arXiv 2404.16162): below about 80% of the
  // free cells the others' waiting costs more (docs/results.md).
  bool rotation_commit = false;
  // Rotation model, with rotation_commit: each new configuration of the whole fleet is the best of
  // this many PIBT runs (1: one run). The first run uses the agents' priorities; each other one
  // raises, by up to kStartNoise, the priorities of the agents in a random box of the map
  // (kStartBox cells each way from an agent's cell), from the same random state, so the runs
  // differ around that box. The run whose cells bring the agents nearest their goals (distance
  // with turns gained, summed over the fleet) is carried out; the first wins ties. With a
  // deadline (set_deadline) no run starts that would end past it. A box keeps each run's
  // difference local, so one sum over a large fleet still tells the runs apart (docs/results.md,
  // session 20).
  int rotation_starts = 1;
  // Rotation model, kCells: an agent that did not get to the cell PIBT chose for it (it turned
  // towards it, or waited for the agent in it) tries that cell first at the next step, unless the
  // caller prefers another (guidance). Replanning from scratch otherwise often sends it, now that it
  // faces the cell, elsewhere, and the turn and the agents queued behind it lose a step
  // (the root of most waits in the jams of fleets of thousands; docs/results.md, session 17).
  bool rotation_keep = false;
  // Rotation model, kCells, without rotation_commit: a pushed agent pays this much more for a
  // cell it must turn towards than for one it faces. A turning agent stays, and its pusher and the
  // agents queued behind stay with it; a cell straight ahead lets the chain move now
  // (docs/results.md, session 18).
  int rotation_push_turn_cost = 0;
  // Steps an agent whose goal is a dead end (a cell with one free neighbour) first waits where it
  // stands, at the lowest priority, before it sets out for it (0 = never). In a packed crowd the
  // occupants of a dead end can leave only through the cell the newcomer queues in (after WPPL,
  // which parks such agents for good; here the goal is only deferred).
  int dead_end_wait = 0;
  // Agents past their dead_end_wait keep waiting while no more than this many wait in all; beyond
  // it, those past their wait set out, the one that has waited longest first (0: each sets out when
  // its wait ends). A packed crowd keeps a few goals deferred at any time, and each waiting agent
  // still sets out once enough others begin to wait after it.
  int dead_end_parked = 0;
  // Rotation model over operations, with a deadline: with 2 or more the search runs in two zones
  // of the map at once, one thread each (search_zones).
  int search_threads = 1;
};

// PIBT as published (the paper configuration and RHCR's fallback): no swap.
inline PibtOptions plain_pibt() {
  PibtOptions o;
  o.swap = false;
  return o;
}

// The step function, reusable on a subset of agents (GD-RHCR moves large groups with it).
class PibtStep {
 public:
  PibtStep(const Grid& grid, int num_agents, uint64_t seed, PibtOptions options = {});

  // Decides next[i] for every agent in `agents` (all agents when empty). `fixed_moves` holds the
  // (from, to) cells of agents outside `agents` whose moves are already decided; PIBT keeps its
  // agents out of both cells. The caller must not fix a move into a cell where one of `agents`
  // stands (PIBT may need to keep that agent in place). `preferred` (per agent, optional; kNoCell
  // for none) is a cell an agent tries first whatever its distance, e.g. the next cell of a
  // guidance path; it must be the agent's cell or a neighbour.
  void step(const WorldView& world, std::vector<Cell>& next,
            const std::vector<int>& agents = {},
            const std::vector<std::pair<Cell, Cell>>& fixed_moves = {},
            const std::vector<Cell>* preferred = nullptr);

  // Agent i's current priority (larger goes first), for tests and diagnostics.
  double priority(int i) const { return priority_[i]; }
  const PibtOptions& options() const { return opt_; }
  long swaps() const { return swaps_; }
  // The next step() stops planning agents at `deadline`. Over operations the check comes before
  // each agent (and every few builds of a chain), and those not built by then keep the operation
  // they hold, which is always valid, or take a cheaper one that meets nobody's (free_takes());
  // the search runs until the deadline. Over cells it comes before
  // each kDeadlineStride agents of the priority order, after the first kDeadlineStride (PIBT over
  // 10,000 agents with turns takes 5-6 ms here), and the agents not planned by then step
  // ahead: into the cell they face (mapf: their nearest neighbour) when it is empty, unclaimed and
  // nearer their goal, else they wait; a call over cells that begins past the deadline plans
  // everyone (its step is over budget anyway). `step_start`, when given, is when the caller's
  // step began: kAuto weighs the first pass against the step's time to the deadline rather than
  // the time left (see over_operations). `limit`, when given, is a hard one: a call over cells
  // that begins past its deadline plans everyone only until then, and the rest step ahead as
  // above. Reading the agents' distances (near_distances) also stops at the limit, when what is
  // left of it would not cover the cheap steps: the agents whose distances were not read wait.
  // One step only (cleared by step()).
  void set_deadline(std::chrono::steady_clock::time_point deadline,
                    std::chrono::steady_clock::time_point step_start = std::chrono::steady_clock::time_point::max(),
                    std::chrono::steady_clock::time_point limit = std::chrono::steady_clock::time_point::max()) {
    deadline_ = deadline, step_start_ = step_start, limit_ = limit;
  }
  long deadline_stops() const { return deadline_stops_; }  // steps stopped so
  long near_cuts() const { return near_cuts_; }  // steps whose distance reads stopped at the limit
  long free_takes() const { return free_takes_; }  // operations taken by agents a cut first pass did not reach
  // When the last call over cells ended its pushes (what follows is turns and bookkeeping).
  std::chrono::steady_clock::time_point pushed_at() const { return pushed_at_; }
  long starts() const { return starts_; }            // rotation_starts: PIBT runs made
  long starts_won() const { return starts_won_; }    // ... configurations a shaken run gave
  long search_rounds() const { return op_search_rounds_; }  // operations: rounds of the search
  long zoned_rounds() const { return op_zoned_rounds_; }   // ... of them in two zones at once
  long stalls() const { return stalls_; }  // operations: calls planned over cells (stalled)
  long operation_calls() const { return op_calls_; }  // rotation model: calls planned over operations
  static constexpr int kStartBox = 4;
  static constexpr double kStartNoise = 5.0;
  static constexpr int kOpSteps = 3;  // actions per operation in the rotation model
  static constexpr int kStallSteps = 20;  // operations: see stalled()
  static constexpr double kOpRoom = 1.5;        // kAuto: see Rotation
  static constexpr double kOpStay = 1.25;       // kAuto: see over_operations
  static constexpr double kOpRetry = 0.995;     // kAuto: see over_operations
  static constexpr double kOpPassWeight = 0.1;  // kAuto: weight of the last first pass in its estimate
  // kAuto's back-off from retries over operations that do not fit. A series of calls over
  // operations shorter than kShortSeries was a retry that did not fit: the next retry waits
  // kFirstHold calls, twice as many after each such retry in a row, up to kMaxHold; a longer
  // series resets the wait. A retry that does not fit costs a slow step and a change of way, so
  // where operations never fit (10 and 30 ms on warehouse_large) they are tried a few times a run,
  // not every hundred steps.
  struct OpRetry {
    static constexpr int kShortSeries = 100, kFirstHold = 100, kMaxHold = 3200;
    int streak = 0;   // calls in a row over operations
    int backoff = 0;  // the wait set after the last series, in calls
    int hold = 0;     // calls left to wait
    void over_operations() { ++streak; }
    void left();  // a series over operations ended
    void tick() { hold -= hold > 0; }
    bool holding() const { return hold > 0; }
  };
  static constexpr double kOpCutScale = 2;      // kAuto: a first pass cut short took at most this times longer
  // kAuto: the whole first pass estimated from a call's setup and building loop (seconds) that
  // reached `reached` agents of `fleet` (see first_pass in pibt_operations.cpp).
  static double first_pass_estimate(double setup, double loop, size_t fleet, size_t reached);
  static constexpr int kDeadlineStride = 64;

 private:
  bool push(const WorldView& world, int ai, int aj, std::vector<Cell>& next);
  void step_ahead(const WorldView& world, int ai, std::vector<Cell>& next);

  // Rotation model: operations (see above; pibt_operations.cpp).
  static constexpr int kMaxOps = 1 << (2 * kOpSteps);
  static constexpr int kOpVisits = 200;  // builds of one agent per round, at most (EPIBT: 10, too few in packed regions)
  static constexpr int kOpDepth = 1000;  // displaced agents built recursively, at most this deep
  struct OpPath {
    Cell cell[kOpSteps + 1];
    Heading heading[kOpSteps + 1];
  };
  struct OpChoice {
    OpPath path;
    int cost = 0;
    int16_t code = 0;
  };
  enum class OpResult { kAccepted, kFailed, kRejected };
  // The search's state where it runs: a zone of the map (0: the whole map; else the cells op_zone_
  // marks with its id), its agents, its round, and the change in the fleet's score it made.
  struct OpZone {
    uint8_t id = 0;
    int axis = 0, lo = INT_MIN, hi = INT_MAX;  // its cells: those whose coordinate along axis (0 x, 1 y) is in [lo, hi]
    int round = 0;
    double score = 0, before = 0;
    std::mt19937_64 rng;
    std::vector<int> agents;
  };
  void plan_operations(const WorldView& world, std::vector<Cell>& next,
                       const std::vector<std::pair<Cell, Cell>>& fixed_moves);
  void order_operations(const WorldView& world, int ai, std::mt19937_64& rng);
  void list_operations(const WorldView& world);
  void retreat_operations(const WorldView& world, int ai);
  const OpChoice& listed(int ai, int code) const;
  void start_operation(const WorldView& world, int ai);
  void wait_in_place(const WorldView& world, int ai);
  OpResult build(const WorldView& world, int ai, bool search, double root, int depth, long& counter, OpZone& z);
  void rebuild(const WorldView& world, int ai, bool search, OpZone& z);
  void first_pass(const WorldView& world, std::chrono::steady_clock::time_point start);
  void take_free_operations(const WorldView& world, size_t from);
  static constexpr int kFreeTries = 8;  // operations an agent a cut first pass did not reach looks at
  long free_takes_ = 0;
  void search_operations(const WorldView& world);
  bool past_deadline(long& counter) const;
  bool stalled();
  bool over_operations(const WorldView& world);
  void size_operations(int n);
  int blocker(int ai, const OpPath& p) const;
  void reserve(int ai, double& score);
  void release(int ai, double& score);
  int& res(int k, Cell c) { return res_[size_t(k - 1) * grid_.num_cells() + c]; }
  int res(int k, Cell c) const { return res_[size_t(k - 1) * grid_.num_cells() + c]; }
  std::vector<int> res_;          // kOpSteps x cells: who holds cell c at t+k; -1 free, kFixed
  // Per agent, what a build writes, one cache line each (two zones' threads write their own agents):
  // the operation it holds (carried on to the next step), the round of its last build, the builds
  // in that round, and whether it is on the build's stack.
  struct alignas(64) OpAgent {
    OpChoice held;
    int visit = 0, visits = 0;
    uint8_t on_stack = 0;
  };
  std::vector<OpAgent> op_;
  std::vector<int> op_held_t_;     // per agent: the timestep its operation was planned at
  std::vector<int> op_wait_cost_;  // per agent: the cost of waiting
  std::vector<double> op_power_;   // per agent: its weight in the score
  std::vector<double> op_key_;     // per agent: its priority this call (larger first)
  std::vector<OpChoice> op_cand_;  // per agent, kMaxOps slots: its operations, best first
  std::vector<int> op_cand_n_;
  bool zone_holds(const OpZone& z, const OpPath& p) const;
  bool deep_in(const OpZone& z, Cell c) const;
  void search_round(const WorldView& world, OpZone& z);
  void search_zones(const WorldView& world, int axis);
  std::vector<uint8_t> op_zone_;  // per cell: the zone it lies in this round (search_zones), 0 none
  int op_round_ = 0;
  double op_score_ = 0;
  long op_search_rounds_ = 0, op_zoned_rounds_ = 0;
  long stalls_ = 0;
  long op_calls_ = 0;
  bool op_auto_ = false;  // kAuto: the last call was planned over operations
  OpRetry op_retry_;
  double op_pass_s_ = 0;  // kAuto: the first pass over operations, in seconds, smoothed (see over_operations)
  std::chrono::steady_clock::time_point deadline_ = std::chrono::steady_clock::time_point::max();
  std::chrono::steady_clock::time_point step_start_ = std::chrono::steady_clock::time_point::max();
  std::chrono::steady_clock::time_point limit_ = std::chrono::steady_clock::time_point::max();
  std::chrono::steady_clock::time_point pushed_at_ = std::chrono::steady_clock::time_point::max();
  double ahead_s_ = 0;  // seconds per agent of the last stop's cheap steps (push_all)
  long deadline_stops_ = 0;
  long near_cuts_ = 0;
  bool near_cut_ = false;  // this call's near_distances stopped at the limit (unread agents: kNotRead)
  static constexpr int kNotRead = -1;  // near_: an agent's distances were not read
  void order_candidates(const WorldView& world, int ai, bool pushed, Cell* cand, int m);
  void push_all(const WorldView& world, std::vector<Cell>& next,
                const std::vector<std::pair<Cell, Cell>>& fixed_moves);
  void sort_by_priority();
  void near_distances(const WorldView& world);
  int near(int i, Cell here, Cell c) const;
  void choose_configuration(const WorldView& world, std::vector<Cell>& next);
  void shake_box(const WorldView& world, const std::vector<double>& base, std::mt19937_64& shake);
  long distance_gain(const WorldView& world, const std::vector<Cell>& next) const;
  void execute_with_turns(const WorldView& world, std::vector<Cell>& next) const;
  void order_candidates_with_turns(const WorldView& world, int ai, bool pushed, Cell* cand, int m);
  int swap_partner(const WorldView& world, int ai, Cell best) const;
  void retreat_order(Cell here, Cell* cand, int m) const;
  bool needs_swap(Cell pusher_at, Cell puller_at, const DistRow& pusher_row,
                  const DistRow& puller_row) const;
  bool can_swap(Cell pusher_at, Cell puller_at) const;
  int passable_neighbours(Cell at, Cell except, Cell* other) const;
  void update_priority(const WorldView& world, int i, Cell goal);
  Cell goal_now(const WorldView& world, int i);
  void end_dead_end_waits(const WorldView& world);
  const std::vector<Cell>* with_kept_cells(const WorldView& world, const std::vector<Cell>* preferred);
  void keep_unreached_cells(const WorldView& world, const std::vector<Cell>& next);
  bool carry_on(const WorldView& world, std::vector<Cell>& next,
                const std::vector<std::pair<Cell, Cell>>& fixed_moves);
  void update_standing(const WorldView& world, int i);
  bool swap_allowed(const WorldView& world, int ai) const;

  const Grid& grid_;
  PibtOptions opt_;
  std::mt19937_64 rng_;
  std::vector<double> priority_;           // elapsed steps + a per-agent tie-breaker in [0,1)
  std::vector<Cell> last_goal_;            // each agent's goal at its last update
  std::vector<int> occupied_now_, occupied_next_;  // agent per cell; -1 free, -2 held by a fixed move
  // Each agent's goal row, kept across calls while its goal stays (one hash look-up per agent
  // per step saved at 10,000 agents); at most one row per agent is held, as during a step.
  std::vector<std::shared_ptr<const DistRow>> rows_;
  std::vector<Cell> row_goal_;  // the goal of each agent's row (kNoCell: none), read without the row
  static constexpr int kNear = kNumHeadings + 1;
  static constexpr size_t kNearAhead = 32;  // agents (near_distances)
  static constexpr size_t kParallelListing = 256;  // agents from which list_operations uses two threads
  // This call's near_distances: per agent, from the 4-neighbour each heading faces, then its cell.
  std::vector<int> near_;
  uint64_t table_id_ = 0;  // the DistTable those rows came from
  std::vector<Cell> goal_of_;                         // each agent's goal, this step
  // Per agent: steps it has stood in its cell, counted once per timestep (rotation_swap_wait).
  std::vector<int> standing_;
  std::vector<Cell> standing_at_;
  std::vector<int> standing_t_;
  std::vector<uint8_t> swapping_;  // per agent: retreating with a swap partner (rotation model)
  std::vector<Cell> kept_, kept_from_, kept_goal_;  // rotation_keep: per agent, the cell it did not get to,
  std::vector<int> kept_t_;                         // from where, for which goal and at which step
  std::vector<Cell> kept_pref_;                     // this call's preferred cells, with the kept ones
  std::vector<Cell> target_;        // rotation_commit: the configuration being carried out
  std::vector<Cell> origin_;        // ... and the cells it was planned from
  int target_steps_ = 0;            // steps spent on it so far (0: none)
  std::vector<Cell> waited_for_;    // dead_end_wait: the goal each agent's wait is for
  std::vector<int> wait_until_;     // ... and the timestep it ends
  std::vector<uint8_t> set_out_;    // ... and whether it has set out (dead_end_parked)
  const std::vector<Cell>* preferred_ = nullptr;
  const std::vector<uint8_t>* immovable_ = nullptr;
  std::vector<int> order_;
  std::vector<std::pair<double, int>> keyed_;  // sort_by_priority's scratch
  long swaps_ = 0;
  long starts_ = 0, starts_won_ = 0;
};

}  // namespace gdrhcr
