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

static double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

nlohmann::json SimResult::to_json() const {
  return {{"steps", steps},
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
          {"step_cpu_time_mean_s", step_cpu_mean_s},
          {"wall_time_s", wall_time_s},
          {"progress",
           {{"agents_late", agents_late},
            {"goals_late", goals_late},
            {"late_at_end", late_at_end},
            {"longest_wait_steps", longest_wait},
            {"max_lateness", max_lateness},
            {"late_rule", "a goal is late after 2 x max(shortest distance, 1) steps without reaching it"}}}};
}

SimResult run_simulation(const Grid& grid, const DistTable& dist, TaskStream& tasks,
                         Planner& planner, const std::vector<Cell>& starts,
                         const SimOptions& options) {
  const auto t_start = Clock::now();
  const int n = static_cast<int>(starts.size());
  const int lookahead = std::max(1, options.lookahead);
  SimResult r;
  r.steps = options.steps;
  r.agents = n;

  std::vector<Cell> pos = starts, next(n, kNoCell);
  StepValidator validator(grid);
  // The start must itself be a valid configuration: free, distinct cells.
  validator.require_valid(pos, pos, -1);

  std::vector<std::vector<Cell>> goals(n);
  // from[i]: the cell agent i's current goal was drawn from. A goal equal to it (only an agent
  // alone in a one-cell component gets one) is a task of length zero and is not counted.
  std::vector<Cell> from = pos;
  for (int i = 0; i < n; ++i) {
    Cell last = pos[i];
    for (int k = 0; k < lookahead; ++k) goals[i].push_back(last = tasks.next_goal(i, last));
  }
  if (options.record_paths) {
    r.paths.assign(n, {});
    for (int i = 0; i < n; ++i) r.paths[i].reserve(options.steps + 1), r.paths[i].push_back(pos[i]);
  }

  // Progress bookkeeping: when each agent got its current goal, its shortest distance then,
  // whether that goal is already counted late, and how long the agent has stood still.
  std::vector<int> got_at(n, 0), still(n, 0);
  std::vector<int> dist0(n);
  std::vector<uint8_t> late(n, 0), ever_late(n, 0);
  for (int i = 0; i < n; ++i) dist0[i] = std::max(1, std::min(dist.get(goals[i].front(), pos[i]), kUnreachable));
  auto check_late = [&](int i, int now) {
    const double ratio = double(now - got_at[i]) / dist0[i];
    if (dist0[i] < kUnreachable) r.max_lateness = std::max(r.max_lateness, ratio);
    if (!late[i] && now - got_at[i] > 2 * dist0[i] && dist0[i] < kUnreachable) {
      late[i] = 1;
      ++r.goals_late;
      if (!ever_late[i]) ever_late[i] = 1, ++r.agents_late;
    }
  };

  double plan_sum = 0, wall_sum = 0, cpu_sum = 0;
  for (int t = 0; t < options.steps; ++t) {
    std::fill(next.begin(), next.end(), kNoCell);
    WorldView view{grid, dist, t, pos, goals};
    const auto t0 = Clock::now();
    const double c0 = process_cpu_s();
    const StepReport rep = planner.plan_step(view, next);
    const double wall = seconds_since(t0);
    cpu_sum += process_cpu_s() - c0;
    wall_sum += wall;
    r.step_wall_max_s = std::max(r.step_wall_max_s, wall);
    if (rep.planned) {
      ++r.planned_steps;
      plan_sum += rep.plan_time_s;
      r.plan_time_max_s = std::max(r.plan_time_max_s, rep.plan_time_s);
    }
    validator.require_valid(pos, next, t);
    for (int i = 0; i < n; ++i) {
      still[i] = (next[i] == pos[i] && next[i] != goals[i].front()) ? still[i] + 1 : 0;
      r.longest_wait = std::max(r.longest_wait, still[i]);
    }
    pos.swap(next);
    for (int i = 0; i < n; ++i) {
      check_late(i, t + 1);
      if (pos[i] != goals[i].front()) continue;
      if (goals[i].front() != from[i]) ++r.goals_reached;
      from[i] = goals[i].front();
      goals[i].erase(goals[i].begin());
      goals[i].push_back(tasks.next_goal(i, goals[i].empty() ? pos[i] : goals[i].back()));
      got_at[i] = t + 1;
      late[i] = 0;
      dist0[i] = std::max(1, std::min(dist.get(goals[i].front(), pos[i]), kUnreachable));
    }
    if (options.record_paths)
      for (int i = 0; i < n; ++i) r.paths[i].push_back(pos[i]);
  }
  r.throughput = options.steps > 0 ? double(r.goals_reached) / options.steps : 0;
  r.plan_time_mean_s = r.planned_steps ? plan_sum / r.planned_steps : 0;
  r.step_wall_mean_s = options.steps > 0 ? wall_sum / options.steps : 0;
  r.step_cpu_mean_s = options.steps > 0 ? cpu_sum / options.steps : 0;
  for (int i = 0; i < n; ++i) r.late_at_end += late[i];
  r.free_flow_throughput = free_flow_throughput(grid, dist, tasks, starts, options.steps);
  r.wall_time_s = seconds_since(t_start);
  return r;
}

double free_flow_throughput(const Grid& grid, const DistTable& dist, const TaskStream& tasks,
                            const std::vector<Cell>& starts, int steps) {
  (void)grid;
  if (steps <= 0) return 0;
  auto replay = tasks.clone_fresh();
  long reached = 0;
  for (int i = 0; i < static_cast<int>(starts.size()); ++i) {
    Cell cur = starts[i];
    long t = 0;
    for (;;) {
      const Cell g = replay->next_goal(i, cur);
      if (g == cur) break;  // no other cell reachable: no task to count
      const int d = dist.get(g, cur);
      if (d >= kUnreachable) break;  // unreachable goal: the agent never gets there
      t += std::max(d, 1);
      if (t > steps) break;
      ++reached;
      cur = g;
    }
  }
  return double(reached) / steps;
}

}  // namespace gdrhcr
