// The anytime part of a step (issue 24): windowed large neighbourhood search over the joint plan of
// the coming steps, after WPPL (Jiang, Zhang, Xiong, Li, Koenig, Li, "Scaling Lifelong Multi-Agent
// Path Finding to More Realistic Settings: Research Challenges and Opportunities", SoCS 2024, arXiv
// 2404.16162), which improves windowed PIBT with LNS in the rest of the League's second; the
// neighbourhoods and the replanning are MAPF-LNS's (Li, Chen, Harabor, Stuckey, Koenig, "Anytime
// Multi-Agent Path Finding via Large Neighborhood Search", IJCAI 2021).
//
// Every step the planner beneath (GD-RHCR, PIBT) first makes a valid step, as without this layer.
// PIBT then carries that step on to a joint plan of `window` steps (each step valid: no vertex or
// edge conflict, every transition one action of the model in force). When the planner beneath and
// the rollout would not fit in the budget (by their times lately), the step has no search and the
// planner beneath gets the budget up to the stop: a rollout cut short is time lost. Each agent's
// cost in the plan is the cost of its steps until it first stands on its goal (its errand is then done,
// and its later steps cost nothing: it stays there, or makes way for others), or, when it does not
// reach it, of all its steps plus its distance (with turns) from where the window leaves it. A step costs what
// the distance rows charge for it: a wait or a turn 1, a forward move 1 plus the step costs in force
// (one-way lanes, traffic; dist_table.hpp), so the search keeps to the lanes as the rows do.
// Then, until the step's deadline: an agent that the plan delays (its cost above its distance) is
// picked at random, with (every other time) the agents in the way of the path it would take alone,
// then the agents standing nearest it. Their paths are taken out and planned again one by one in a
// random order, each by space-time A* over the model's states around the paths of all the others
// (an agent that finds no path goes first in the next try, up to four tries); the new paths are
// kept when they cost no more in sum (so the search drifts across equal plans), else the old ones
// come back. A search that a long run of neighbourhoods has not lowered doubles their size, up to
// four times the first, then stops. With threads, stripes of the map whose searches cannot touch
// the same cell are searched at once, one thread each, then everyone together. The first step of
// the final plan is executed.
// Only plans free of conflicts are ever held, so what is executed is valid whenever the search
// stops. Robots that cannot move and blocked cells (the ROS node's offline robots and late robots'
// cells) turn the search off for that step: the step of the planner beneath is executed as it is.
#pragma once

#include <chrono>
#include <memory>
#include <random>
#include <vector>

#include "gdrhcr/pibt.hpp"
#include "gdrhcr/planner.hpp"

namespace gdrhcr {

struct WindowLnsConfig {
  int window = 0;          // steps of the joint plan (0 = off: the planner beneath alone)
  int neighbourhood = 8;   // agents planned again together
  int iterations = 0;      // neighbourhoods tried per step (0 = until the deadline)
  double step_budget_s = 0;  // the step's wall-clock budget (0 = none; the caller's may be smaller)
  int threads = 1;           // zones of the map searched at once, one thread each (the planner's pool)
  // Of the budget: the planner beneath gets this share, and the search stops at kStopShare.
  static constexpr double kInnerShare = 0.5;
  static constexpr double kStopShare = 0.95;
  static constexpr int kMaxExpansions = 20000;  // per A*; a search cut short fails
  // Of the search's time, with threads: the zones searched at once; then one search over everyone.
  static constexpr double kZonedShare = 0.75;
  uint64_t seed = 0;
};

class WindowLns : public Planner {
 public:
  // `rollout` are the options of the PIBT that carries the first step on (its own instance).
  // It plans in whichever action model each step's world is in, as the planner beneath does; the
  // search's tables are made for `model` at once.
  WindowLns(std::unique_ptr<Planner> inner, const Grid& grid, int num_agents, WindowLnsConfig config,
            PibtOptions rollout, ActionModel model);
  ~WindowLns() override;
  std::string name() const override { return inner_->name(); }
  StepReport plan_step(const WorldView& world, std::vector<Cell>& next) override;
  nlohmann::json params() const override;
  // The planner beneath's stats, plus lns_* counters: steps searched, neighbourhoods tried and
  // kept, the plan cost the search took off, and the time spent.
  nlohmann::json stats() const override;
  std::vector<PlannerGroup> groups() const override { return inner_->groups(); }
  // The last step's joint plan when the search ran; else the planner beneath's (GD-RHCR answers
  // from its guidance paths, which the ROS executor's catch-up reads).
  std::vector<Cell> planned_path(int agent) const override;
  Cell intended_next(int agent, Cell at) const override;

  // The joint plan of the last step, per agent: poses at t = 0 .. window (empty when the search
  // did not run), and its summed cost (as above). For tests.
  const std::vector<std::vector<Pose>>& plan() const { return paths_; }
  long plan_cost() const;

 private:
  struct Search;  // the scratch tables of one A*
  struct Worker;  // one thread's search: its zone, its delayed agents, its A*, its counters
  using Clock = std::chrono::steady_clock;
  // False when `stop` passed before the window was filled.
  bool rollout(const WorldView& world, const std::vector<Cell>& next, Clock::time_point stop);
  long cost_of(const WorldView& world, int agent, const std::vector<Pose>& path) const;
  size_t states(ActionModel model) const;  // the A*'s: (t, reached, cell in a box around the start, heading)
  static int step_cost(const WorldView& world, Pose a, Pose b);
  void reserve(int agent, const std::vector<Pose>& path, bool on);
  bool replan(const WorldView& world, int agent, std::vector<Pose>& path, Search& s);
  std::vector<int> neighbourhood(const WorldView& world, int seed_agent, Worker& w);
  void add_blockers(const WorldView& world, int seed_agent, std::vector<int>& agents, const Worker& w) const;
  // One neighbourhood (given up, as a failure, when `stop` passes between two of its A*s).
  bool improve_once(const WorldView& world, Worker& w, Clock::time_point stop);
  // Neighbourhoods until `stop`, `iterations` (> 0) or a stale run; false after a stale run.
  bool search(const WorldView& world, Worker& w, Clock::time_point stop, long iterations);
  long search_zones(const WorldView& world, int zones, Clock::time_point stop, long iterations);
  // The zones of this step, one per worker from the first, and their delayed agents: stripes along
  // the map's longer side, cut at the delayed agents' quantiles, each leaving out the agents within
  // a margin of its borders so that no two zones' searches read or write the same cell. As many
  // zones as workers when they fit (each holds a delayed agent, and together at least half of
  // them), else fewer; 1 = none (the search runs over everyone alone).
  int make_zones(const WorldView& world);
  int& at(int t, Cell c) { return reserved_[static_cast<size_t>(t) * cells_ + c]; }
  int at(int t, Cell c) const { return reserved_[static_cast<size_t>(t) * cells_ + c]; }

  std::unique_ptr<Planner> inner_;
  const Grid& grid_;
  WindowLnsConfig cfg_;
  PibtStep pibt_;
  int cells_;
  std::vector<std::vector<Pose>> paths_;
  std::vector<long> cost_, lower_;  // per agent: its cost in the plan, its distance (no plan costs less)
  std::vector<int> delayed_;        // the agents whose cost is above their distance, at the step's start
  std::vector<int> reserved_;  // per (t, cell): the agent planned there, or -1
  std::vector<std::shared_ptr<const DistRow>> rows_;
  std::vector<std::unique_ptr<Worker>> workers_;  // the first also searches everyone after the zones
  std::vector<std::vector<Pose>> last_;  // the plan of the step before
  int last_timestep_ = -2;
  double inner_s_ = 0;         // the planner beneath's time with its share lately (0 = not yet)
  double rollout_step_s_ = 0;  // one rollout step's time lately (0 = no rollout yet)
  long steps_searched_ = 0, rollouts_cut_ = 0, rollouts_skipped_ = 0, stale_stops_ = 0, zoned_steps_ = 0;
  double search_s_ = 0;
};

}  // namespace gdrhcr
