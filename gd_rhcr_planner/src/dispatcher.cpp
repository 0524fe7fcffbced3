// Batch dispatch by minimum total travel; see dispatcher.hpp.
#include "gd_rhcr_planner/dispatcher.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include "gd_rhcr_planner/assignment.hpp"
#include "gdrhcr/params.hpp"

namespace gd_rhcr_planner {

DispatchPolicy parse_dispatch_policy(const std::string& name) {
  if (name == "batch") return DispatchPolicy::kBatch;
  if (name == "greedy") return DispatchPolicy::kGreedy;
  throw gdrhcr::ParamError("~dispatcher must be 'batch' or 'greedy', not '" + name + "'");
}

const char* dispatch_policy_name(DispatchPolicy p) { return p == DispatchPolicy::kBatch ? "batch" : "greedy"; }

void DispatchParams::validate() const {
  if (finish_horizon < 0) throw gdrhcr::ParamError("~dispatch_finish_horizon must be >= 0 cells");
  if (switch_margin < 0) throw gdrhcr::ParamError("~dispatch_switch_margin must be >= 0 cells");
  if (max_tasks < 1) throw gdrhcr::ParamError("~dispatch_max_tasks must be >= 1");
  if (!(age_weight >= 0 && age_weight <= 100)) throw gdrhcr::ParamError("~dispatch_age_weight must be in [0, 100]");
}

namespace {
constexpr int64_t kNoRoute = int64_t(1) << 40;  // a pair that must not be matched

// The batch: highest priority first, then lowest id (oldest); at most max_tasks.
std::vector<const DispatchTask*> batch_tasks(const std::vector<DispatchTask>& tasks_in, const DispatchParams& params) {
  std::vector<const DispatchTask*> tasks;
  for (auto& t : tasks_in) tasks.push_back(&t);
  std::stable_sort(tasks.begin(), tasks.end(), [](const DispatchTask* a, const DispatchTask* b) {
    return a->priority != b->priority ? a->priority > b->priority : a->id < b->id;
  });
  if (static_cast<int>(tasks.size()) > params.max_tasks) tasks.resize(params.max_tasks);
  return tasks;
}

// Travel cost of robots[rows[r]] to tasks[c] (row-major, rows.size() x tasks.size()): the robot's
// eta plus the distance to the pickup, less the task's age bonus, less the switch margin for the
// task's own holder; kNoRoute where the pickup cannot be reached.
std::vector<int64_t> cost_matrix(const std::vector<DispatchRobot>& robots, const std::vector<int>& rows,
                                 const std::vector<const DispatchTask*>& tasks, const gdrhcr::DistTable& dist,
                                 const DispatchParams& params) {
  const size_t nr = rows.size(), nc = tasks.size();
  std::vector<int64_t> cost(nr * nc);
  for (size_t c = 0; c < nc; ++c) {
    const DispatchTask& t = *tasks[c];
    const auto row = dist.row(t.pickup);
    // Waiting lowers a task's cost by the same amount for every robot: it only decides which
    // tasks are served when there are fewer robots than tasks.
    const int64_t age = static_cast<int64_t>(std::llround(params.age_weight * t.waited));
    for (size_t r = 0; r < nr; ++r) {
      const DispatchRobot& rob = robots[rows[r]];
      const int d = (*row)[rob.from];
      int64_t v = d >= gdrhcr::kUnreachable ? kNoRoute : int64_t(rob.eta) + d - age;
      if (d < gdrhcr::kUnreachable && rob.id == t.holder) v -= params.switch_margin;
      cost[r * nc + c] = v;
    }
  }
  return cost;
}

// Minimum total cost matching, one priority level at a time (higher levels first, each with the
// robots the levels before left): task id -> index in `robots`.
std::map<uint64_t, int> match_by_priority(const std::vector<DispatchRobot>& robots,
                                          const std::vector<const DispatchTask*>& tasks, const gdrhcr::DistTable& dist,
                                          const DispatchParams& params) {
  std::vector<char> robot_used(robots.size(), 0);
  std::map<uint64_t, int> match;
  for (size_t begin = 0; begin < tasks.size();) {
    size_t end = begin;
    while (end < tasks.size() && tasks[end]->priority == tasks[begin]->priority) ++end;
    std::vector<int> rows;
    for (size_t i = 0; i < robots.size(); ++i)
      if (!robot_used[i]) rows.push_back(static_cast<int>(i));
    if (rows.empty()) break;
    const std::vector<const DispatchTask*> level(tasks.begin() + begin, tasks.begin() + end);
    const int nr = static_cast<int>(rows.size()), nc = static_cast<int>(level.size());
    const std::vector<int64_t> cost = cost_matrix(robots, rows, level, dist, params);
    const auto col_of_row = min_cost_assignment(cost, nr, nc);
    for (int r = 0; r < nr; ++r) {
      const int c = col_of_row[r];
      if (c < 0 || cost[static_cast<size_t>(r) * nc + c] >= kNoRoute / 2) continue;
      robot_used[rows[r]] = 1;
      match[level[c]->id] = rows[r];
    }
    begin = end;
  }
  return match;
}

// Each batch task's holder after the matching (out.changes, out.stats). Robots about to finish
// only reserve: their task stays where it is (queued, or with its robot when that robot got
// nothing else). Returns the task each robot takes now (robot id -> task).
std::map<int, uint64_t> decide_holders(const std::vector<DispatchRobot>& robots,
                                       const std::vector<const DispatchTask*>& tasks,
                                       const std::map<uint64_t, int>& match, const gdrhcr::DistTable& dist,
                                       BatchResult& out) {
  std::map<int, uint64_t> new_task_of;
  for (auto& [task, ri] : match)
    if (robots[ri].can_take_now()) new_task_of[robots[ri].id] = task;
  for (const DispatchTask* t : tasks) {
    auto m = match.find(t->id);
    int holder = t->holder;
    if (m != match.end() && robots[m->second].can_take_now()) {
      holder = robots[m->second].id;
      if (holder != t->holder) out.stats.travel += (*dist.row(t->pickup))[robots[m->second].from];
    } else {
      if (m != match.end()) ++out.stats.reserved;
      // Its robot took another task in this batch: back to the queue.
      if (holder >= 0 && new_task_of.count(holder) && new_task_of[holder] != t->id) holder = -1;
    }
    if (holder == t->holder) continue;
    out.changes.push_back({t->id, holder});
    if (holder >= 0 && t->holder < 0) ++out.stats.assigned;
    if (holder >= 0 && t->holder >= 0) ++out.stats.reassigned;
  }
  return new_task_of;
}

}  // namespace

BatchResult solve_batch(const std::vector<DispatchRobot>& robots, const std::vector<DispatchTask>& tasks_in,
                        const gdrhcr::DistTable& dist, const DispatchParams& params) {
  const auto t0 = std::chrono::steady_clock::now();
  BatchResult out;
  const std::vector<const DispatchTask*> tasks = batch_tasks(tasks_in, params);
  out.stats.robots = static_cast<int>(robots.size());
  out.stats.tasks = static_cast<int>(tasks.size());
  const std::map<uint64_t, int> match = match_by_priority(robots, tasks, dist, params);
  std::map<int, uint64_t> new_task_of = decide_holders(robots, tasks, match, dist, out);
  // Tasks outside the batch (beyond max_tasks) whose robot took a batch task go back to the queue.
  for (auto& t : tasks_in) {
    if (t.holder < 0 || !new_task_of.count(t.holder) || new_task_of[t.holder] == t.id) continue;
    if (std::find_if(out.changes.begin(), out.changes.end(), [&](auto& ch) { return ch.task == t.id; }) !=
        out.changes.end())
      continue;
    out.changes.push_back({t.id, -1});
  }
  out.stats.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

// Fleet's rule before issue 14: queued tasks by priority (high first) then id, each to the
// nearest free robot (ties to the lower id); assigned tasks stay; robots about to finish wait.
DispatchStats Dispatcher::greedy(const std::vector<DispatchRobot>& robots, const std::vector<DispatchTask>& tasks,
                                 const gdrhcr::DistTable& dist, Fleet& fleet) const {
  DispatchStats st;
  std::vector<int> idle;
  for (auto& r : robots)
    if (r.can_take_now() && fleet.robot(r.id).task < 0) idle.push_back(r.id);
  std::vector<const DispatchTask*> queued;
  for (auto& t : tasks)
    if (t.holder < 0) queued.push_back(&t);
  std::stable_sort(queued.begin(), queued.end(), [](const DispatchTask* a, const DispatchTask* b) {
    return a->priority != b->priority ? a->priority > b->priority : a->id < b->id;
  });
  st.robots = static_cast<int>(idle.size());
  st.tasks = static_cast<int>(queued.size());
  std::vector<Fleet::Reassignment> batch;
  for (const DispatchTask* t : queued) {
    if (idle.empty()) break;
    const auto row = dist.row(t->pickup);
    int best = -1, best_d = gdrhcr::kUnreachable;
    for (size_t k = 0; k < idle.size(); ++k) {
      const int d = (*row)[fleet.robot(idle[k]).cell];
      if (d < best_d) best_d = d, best = static_cast<int>(k);
    }
    if (best < 0) continue;
    batch.push_back({t->id, idle[best]});
    st.travel += best_d;
    ++st.assigned;
    idle.erase(idle.begin() + best);
  }
  fleet.apply_assignments(batch);
  return st;
}

Dispatcher::Dispatcher(DispatchPolicy policy, DispatchParams params) : policy_(policy), params_(params) {
  params_.validate();
}

DispatchStats Dispatcher::dispatch(Fleet& fleet, const gdrhcr::DistTable& dist, const std::vector<uint8_t>& unavailable) {
  ++tick_;
  fleet.set_auto_assign(false);  // both policies assign here (greedy as Fleet did, honouring `unavailable`)
  std::map<Cell, int> offline_at;
  for (int r = 0; r < fleet.num_robots(); ++r)
    if (fleet.robot(r).reported && fleet.robot(r).offline) offline_at.emplace(fleet.robot(r).cell, r);
  auto off = [&](int r) { return r < static_cast<int>(unavailable.size()) && unavailable[r]; };

  std::vector<DispatchRobot> robots;
  std::vector<DispatchTask> tasks;
  for (int r = 0; r < fleet.num_robots(); ++r) {
    const RobotRecord& rob = fleet.robot(r);
    if (!rob.reported || rob.offline || off(r)) continue;
    DispatchRobot d;
    d.id = r;
    d.from = rob.cell;
    if (rob.task >= 0) {
      const TaskRecord* t = fleet.task(static_cast<uint64_t>(rob.task));
      if (t && t->state == kPicked) {  // carrying a load: a candidate only when about to finish
        const int left = dist.get(t->delivery, rob.cell);
        if (left > params_.finish_horizon) continue;
        d.from = t->delivery;
        d.eta = left;
      }
    }
    robots.push_back(d);
  }
  std::unordered_map<uint64_t, uint64_t> seen;
  for (auto& [id, t] : fleet.tasks()) {
    if (!(t.state == kQueued || t.state == kAssigned)) continue;
    if (offline_at.count(t.pickup) || offline_at.count(t.delivery)) continue;  // waits for the robot to leave
    DispatchTask d;
    d.id = id;
    d.pickup = t.pickup;
    d.priority = t.priority;
    d.holder = t.state == kAssigned ? t.robot : -1;
    if (d.holder < 0) {
      auto it = queued_since_.find(id);
      const uint64_t since = it == queued_since_.end() ? tick_ : it->second;
      seen[id] = since;
      d.waited = static_cast<double>(tick_ - since);
    }
    tasks.push_back(d);
  }
  queued_since_.swap(seen);
  if (policy_ == DispatchPolicy::kGreedy) {
    const auto t0 = std::chrono::steady_clock::now();
    DispatchStats st = greedy(robots, tasks, dist, fleet);
    st.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return st;
  }
  BatchResult res = solve_batch(robots, tasks, dist, params_);
  fleet.apply_assignments(res.changes);
  return res.stats;
}

}  // namespace gd_rhcr_planner
