#include "gdrhcr/simulator.hpp"

#include <algorithm>
#include <chrono>
#include <ctime>

#include "gdrhcr/validator.hpp"

namespace gdrhcr {

using Clock = std::chrono::steady_clock;

static double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The q-quantile of `values` (the value at rank q * n of the sorted values, as tools/bench_lorr.py
// counts the Start-Kit's), 0 for none.
static double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * static_cast<double>(values.size())));
  std::nth_element(values.begin(), values.begin() + static_cast<long>(k), values.end());
  return values[k];
}

// Blocks of SimResult::kTimelineSteps steps that `steps` steps fill, the last one possibly short.
static size_t blocks(int steps) {
  return steps > 0 ? (steps + SimResult::kTimelineSteps - 1) / SimResult::kTimelineSteps : 0;
}

static double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

nlohmann::json ErrandSteps::to_json() const {
  const double n = errands > 0 ? double(errands) : 1.0;
  return {{"errands", errands},
          {"steps_per_errand", steps() / n},
          {"forward_per_errand", forward / n},
          {"turns_per_errand", turns / n},
          {"waits_per_errand", waits / n}};
}

nlohmann::json SimResult::to_json() const {
  return {{"action_model", action_model_name(action_model)},
          {"steps", steps},
          {"agents", agents},
          {"goals_reached", goals_reached},
          {"throughput", throughput},
          {"free_flow_throughput", free_flow_throughput},
          {"collisions", collisions},
          {"planned_steps", planned_steps},
          {"plan_time_mean_s", plan_time_mean_s},
          {"plan_time_max_s", plan_time_max_s},
          {"step_wall_time_mean_s", step_wall_mean_s},
          {"step_wall_time_max_s", step_wall_max_s},
          {"step_wall_time_p99_s", step_wall_p99_s},
          {"step_cpu_time_mean_s", step_cpu_mean_s},
          {"wall_time_s", wall_time_s},
          {"goals_timeline", {{"block_steps", kTimelineSteps}, {"goals", goals_timeline}}},
          {"errand_steps", {{"reached", errand_steps.to_json()}, {"free_flow", free_flow_errand_steps.to_json()}}},
          {"progress",
           {{"agents_late", agents_late},
            {"goals_late", goals_late},
            {"late_at_end", late_at_end},
            {"longest_wait_steps", longest_wait},
            {"max_lateness", max_lateness},
            {"late_rule", "a goal is late after 2 x max(shortest distance, 1) steps without reaching it"}}}};
}

namespace {

// One simulation run: the agents' cells and goals, the planner's steps validated one by one, and
// the progress figures of the result.
class Run {
 public:
  Run(const Grid& grid, const DistTable& dist, TaskStream& tasks, Planner& planner,
      const std::vector<Cell>& starts, const SimOptions& options)
      : grid_(grid), dist_(dist), tasks_(tasks), planner_(planner), opt_(options), n_(static_cast<int>(starts.size())),
        pos_(starts), next_(n_, kNoCell), goals_(n_), errand_(n_), validator_(grid, options.action_model),
        got_at_(n_, 0), still_(n_, 0), dist0_(n_), late_(n_, 0), ever_late_(n_, 0), leg_(n_) {
    r_.steps = options.steps;
    r_.agents = n_;
    r_.action_model = options.action_model;
    r_.goals_timeline.assign(blocks(options.steps), 0);
    init_headings();
    validator_.require_valid(pos_, pos_, -1, heads(), heads());  // the start: free, distinct cells
    const int lookahead = std::max(1, options.lookahead);
    for (int i = 0; i < n_; ++i) {
      for (int k = 0; k < lookahead; ++k) hand_out_goal(i);
      dist0_[i] = shortest(i);
    }
    if (opt_.record_paths) {
      r_.paths.assign(n_, {});
      for (int i = 0; i < n_; ++i) r_.paths[i].reserve(opt_.steps + 1), r_.paths[i].push_back(pos_[i]);
      if (rotation()) r_.headings.assign(n_, {});
      for (int i = 0; rotation() && i < n_; ++i) r_.headings[i].push_back(head_[i]);
    }
  }

  SimResult run(const std::vector<Cell>& starts, Clock::time_point t_start) {
    int steps = 0;
    for (; steps < opt_.steps; ++steps) {
      if (steps > 0 && opt_.wall_limit_s > 0 && seconds_since(t_start) > opt_.wall_limit_s) break;
      plan(steps);
      advance(steps);
    }
    r_.steps = steps;
    r_.goals_timeline.resize(blocks(steps));
    r_.throughput = steps > 0 ? double(r_.goals_reached) / steps : 0;
    r_.plan_time_mean_s = r_.planned_steps ? plan_sum_ / r_.planned_steps : 0;
    r_.step_wall_mean_s = steps > 0 ? wall_sum_ / steps : 0;
    r_.step_wall_p99_s = percentile(walls_, 0.99);
    r_.step_cpu_mean_s = steps > 0 ? cpu_sum_ / steps : 0;
    for (int i = 0; i < n_; ++i) r_.late_at_end += late_[i];
    if (opt_.free_flow)
      r_.free_flow_throughput =
          free_flow_throughput(grid_, dist_, tasks_, starts, steps, &start_head_, &r_.free_flow_errand_steps);
    r_.wall_time_s = seconds_since(t_start);
    return std::move(r_);
  }

 private:
  bool rotation() const { return opt_.action_model == ActionModel::kRotation; }
  const std::vector<Heading>* heads() const { return rotation() ? &head_ : nullptr; }
  int shortest(int i) const {
    const int d = rotation() ? dist_.get(goals_[i].front(), pos_[i], head_[i]) : dist_.get(goals_[i].front(), pos_[i]);
    return std::max(1, std::min(d, kUnreachable));
  }

  // Rotation: the start headings (default east), checked against the fleet and the DistTable.
  void init_headings() {
    if (dist_.action_model() != opt_.action_model)
      throw std::invalid_argument(std::string("simulation in the ") + action_model_name(opt_.action_model) +
                                  " action model needs a distance table built in it, got " +
                                  action_model_name(dist_.action_model()));
    if (!rotation()) return;
    start_head_ = opt_.start_headings.empty() ? std::vector<Heading>(n_, kEast) : opt_.start_headings;
    if (static_cast<int>(start_head_.size()) != n_)
      throw std::invalid_argument("start headings: " + std::to_string(start_head_.size()) + " for " +
                                  std::to_string(n_) + " agents");
    head_ = start_head_;
    next_head_.assign(n_, kNoHeading);
  }

  // The planner's step, timed and validated (a collision throws CollisionError).
  void plan(int t) {
    std::fill(next_.begin(), next_.end(), kNoCell);
    std::fill(next_head_.begin(), next_head_.end(), kNoHeading);
    WorldView view{grid_, dist_, t, pos_, goals_};
    if (rotation()) {
      view.action_model = ActionModel::kRotation;
      view.headings = &head_;
      view.next_headings = &next_head_;
    }
    const auto t0 = Clock::now();
    const double c0 = process_cpu_s();
    const StepReport rep = planner_.plan_step(view, next_);
    const double wall = seconds_since(t0);
    cpu_sum_ += process_cpu_s() - c0;
    wall_sum_ += wall;
    walls_.push_back(wall);
    r_.step_wall_max_s = std::max(r_.step_wall_max_s, wall);
    if (rep.planned) {
      ++r_.planned_steps;
      plan_sum_ += rep.plan_time_s;
      r_.plan_time_max_s = std::max(r_.plan_time_max_s, rep.plan_time_s);
    }
    validator_.require_valid(pos_, next_, t, heads(), rotation() ? &next_head_ : nullptr);
  }

  // Agent i's next goal, drawn from its last one (or its cell), and whether it is an errand.
  void hand_out_goal(int i) {
    const Cell from = goals_[i].empty() ? pos_[i] : goals_[i].back();
    goals_[i].push_back(tasks_.next_goal(i, from));
    errand_[i].push_back(tasks_.is_errand(i, goals_[i].back(), from));
  }

  // Executes the step: agents on their goal get the next one. A goal that is no errand
  // (TaskStream::is_errand) is not counted.
  void advance(int t) {
    for (int i = 0; i < n_; ++i) {
      still_[i] = (next_[i] == pos_[i] && next_[i] != goals_[i].front()) ? still_[i] + 1 : 0;
      r_.longest_wait = std::max(r_.longest_wait, still_[i]);
      count_action(i);
    }
    pos_.swap(next_);
    head_.swap(next_head_);
    for (int i = 0; i < n_; ++i) {
      check_late(i, t + 1);
      if (pos_[i] != goals_[i].front()) continue;
      if (errand_[i].front()) {
        ++r_.goals_reached;
        ++r_.goals_timeline[t / SimResult::kTimelineSteps];
        add_leg(r_.errand_steps, leg_[i]);
      }
      leg_[i] = {};
      goals_[i].erase(goals_[i].begin());
      errand_[i].erase(errand_[i].begin());
      hand_out_goal(i);
      got_at_[i] = t + 1;
      late_[i] = 0;
      dist0_[i] = shortest(i);
    }
    if (opt_.record_paths)
      for (int i = 0; i < n_; ++i) r_.paths[i].push_back(pos_[i]);
    if (opt_.record_paths && rotation())
      for (int i = 0; i < n_; ++i) r_.headings[i].push_back(head_[i]);
  }

  // The action agent i takes this step, counted on its current goal's leg.
  void count_action(int i) {
    ErrandSteps& l = leg_[i];
    if (next_[i] != pos_[i]) ++l.forward;
    else if (rotation() && next_head_[i] != head_[i]) ++l.turns;
    else ++l.waits;
  }

  static void add_leg(ErrandSteps& sum, const ErrandSteps& leg) {
    ++sum.errands;
    sum.forward += leg.forward, sum.turns += leg.turns, sum.waits += leg.waits;
  }

  // A goal is late once its agent has spent more than twice its shortest distance on it.
  void check_late(int i, int now) {
    const double ratio = double(now - got_at_[i]) / dist0_[i];
    if (dist0_[i] < kUnreachable) r_.max_lateness = std::max(r_.max_lateness, ratio);
    if (!late_[i] && now - got_at_[i] > 2 * dist0_[i] && dist0_[i] < kUnreachable) {
      late_[i] = 1;
      ++r_.goals_late;
      if (!ever_late_[i]) ever_late_[i] = 1, ++r_.agents_late;
    }
  }

  const Grid& grid_;
  const DistTable& dist_;
  TaskStream& tasks_;
  Planner& planner_;
  const SimOptions& opt_;
  const int n_;
  SimResult r_;
  std::vector<Cell> pos_, next_;
  std::vector<Heading> head_, next_head_, start_head_;  // rotation only
  std::vector<std::vector<Cell>> goals_;
  std::vector<std::vector<uint8_t>> errand_;  // per goal in goals_: counted when reached
  StepValidator validator_;
  // Progress: when each agent got its current goal, its shortest distance then, whether that goal
  // is counted late, and how long the agent has stood still.
  std::vector<int> got_at_, still_, dist0_;
  std::vector<uint8_t> late_, ever_late_;
  std::vector<ErrandSteps> leg_;  // per agent: the steps on its current goal so far
  double plan_sum_ = 0, wall_sum_ = 0, cpu_sum_ = 0;
  std::vector<double> walls_;  // plan_step's wall time per step
};

}  // namespace

SimResult run_simulation(const Grid& grid, const DistTable& dist, TaskStream& tasks,
                         Planner& planner, const std::vector<Cell>& starts,
                         const SimOptions& options) {
  const auto t_start = Clock::now();
  return Run(grid, dist, tasks, planner, starts, options).run(starts, t_start);
}

namespace {
// Rotation: walks `p` along a shortest path over (cell, heading) states to row's goal (forward
// first among equally short actions) and returns its length; *turns counts its turns.
int walk_to_goal(const Grid& grid, const DistRow& row, Pose& p, int* turns) {
  int steps = 0;
  for (int d = row.at(p.cell, p.heading); d > 0; --d, ++steps) {
    for (Action a : {Action::kForward, Action::kClockwise, Action::kCounterClockwise}) {
      const Pose q = apply_action(grid, p, a);
      if (q.cell != kNoCell && row.at(q.cell, q.heading) == d - 1) {
        *turns += a != Action::kForward;
        p = q;
        break;
      }
    }
  }
  return steps;
}
}  // namespace

double free_flow_throughput(const Grid& grid, const DistTable& dist, const TaskStream& tasks,
                            const std::vector<Cell>& starts, int steps, const std::vector<Heading>* start_headings,
                            ErrandSteps* errand_steps) {
  if (errand_steps) *errand_steps = {};
  if (steps <= 0) return 0;
  if (dist.step_costs().any()) {  // the bound is over true shortest paths: every step costs 1
    const DistTable unit(grid, dist.action_model(), dist.budget_bytes());
    return free_flow_throughput(grid, unit, tasks, starts, steps, start_headings, errand_steps);
  }
  const bool rotation = dist.action_model() == ActionModel::kRotation;
  auto replay = tasks.clone_fresh();
  long reached = 0;
  for (int i = 0; i < static_cast<int>(starts.size()); ++i) {
    Cell cur = starts[i];
    Pose pose{cur, start_headings && !start_headings->empty() ? (*start_headings)[i] : kEast};
    long t = 0;
    for (;;) {
      const Cell g = replay->next_goal(i, cur);
      if (!replay->is_errand(i, g, cur)) break;  // no task to count
      int d = dist.get(g, cur);
      if (d >= kUnreachable) break;  // unreachable goal: the agent never gets there
      int turns = 0;
      if (rotation) d = walk_to_goal(grid, *dist.row(g), pose, &turns);
      t += std::max(d, 1);
      if (t > steps) break;
      ++reached;
      if (errand_steps) {
        ErrandSteps& e = *errand_steps;
        ++e.errands;
        e.forward += d - turns, e.turns += turns, e.waits += std::max(d, 1) - d;
      }
      cur = g;
    }
  }
  return double(reached) / steps;
}

}  // namespace gdrhcr
