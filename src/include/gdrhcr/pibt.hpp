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
// Rotation model (issue 23, LoRR's MAPF_T; action_model.hpp): PIBT over (cell, heading) states.
// An agent's candidates are its actions: forward (F) into the cell it faces, a quarter turn either
// way (R, C) or a wait (W), ordered by the distance to its goal from the state each leads to
// (DistRow::at, turns counted). Only F leaves the cell, so an agent that turns or waits keeps its
// cell for t+1, and priority inheritance sees it: an agent pushed out of its cell can vacate it
// only by F into the cell it faces (never into its pusher's cell). When it cannot (it faces a wall,
// an obstacle, its pusher or a cell it cannot clear), the push fails at once, the pusher tries its
// next action, and the pushed agent turns towards its best way out (the free neighbour nearest its
// own goal, not the pusher's cell). Giving way then takes more than one step, so the push is kept
// as a short operation (turn, [turn,] forward; after EPIBT's multi-step operations, Nagorny, LoRR
// 2024 winner, arXiv 2511.09193): until it has left its cell or the operation's steps are over, the
// pushed agent keeps the pusher's priority when that is higher and prefers the operation's next
// action over its own way. Without that it turns back towards its goal at the next step, in front
// of the same pusher, for ever. Swap emulation is off in this model (its pull needs a sideways
// move).
#pragma once

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

 private:
  bool push(const WorldView& world, int ai, int aj, std::vector<Cell>& next);
  // Rotation model (see above).
  bool push_rotation(const WorldView& world, int ai, int aj, std::vector<Cell>& next);
  bool try_forward(const WorldView& world, int ai, int aj, std::vector<Cell>& next);
  void stay(const WorldView& world, int ai, Heading h, std::vector<Cell>& next);
  int order_actions(const WorldView& world, int ai, Action* acts);
  Heading way_out(const WorldView& world, int ai, int pusher);
  double effective_priority(const WorldView& world, int i) const;
  // Rotation: an agent giving way (see above): where it stands, the heading it leaves by, the
  // priority it inherited and the last timestep of the operation.
  struct GiveWay {
    Cell at = kNoCell;
    Heading toward = kNoHeading;
    double priority = 0;
    int until = -1;
  };
  std::vector<GiveWay> give_way_;
  void order_candidates(int ai, Cell* cand, int m);
  int swap_partner(const WorldView& world, int ai, Cell best) const;
  bool needs_swap(Cell pusher_at, Cell puller_at, const DistRow& pusher_row,
                  const DistRow& puller_row) const;
  bool can_swap(Cell pusher_at, Cell puller_at) const;
  int passable_neighbours(Cell at, Cell except, Cell* other) const;
  void update_priority(const WorldView& world, int i, Cell goal);

  const Grid& grid_;
  PibtOptions opt_;
  std::mt19937_64 rng_;
  std::vector<double> priority_;           // elapsed steps + a per-agent tie-breaker in [0,1)
  std::vector<Cell> last_goal_;            // each agent's goal at its last update
  std::vector<int> occupied_now_, occupied_next_;  // agent per cell; -1 free, -2 held by a fixed move
  // Each agent's goal row, kept across calls while its goal stays (one hash look-up per agent
  // per step saved at 10,000 agents); at most one row per agent is held, as during a step.
  std::vector<std::shared_ptr<const DistRow>> rows_;
  uint64_t table_id_ = 0;  // the DistTable those rows came from
  std::vector<Cell> goal_of_;                         // each agent's goal, this step
  const std::vector<Cell>* preferred_ = nullptr;
  const std::vector<uint8_t>* immovable_ = nullptr;
  std::vector<Heading>* next_headings_ = nullptr;  // rotation: the call's output headings
  std::vector<int> order_;
  long swaps_ = 0;
};

}  // namespace gdrhcr
