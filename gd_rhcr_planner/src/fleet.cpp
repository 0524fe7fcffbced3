#include "gd_rhcr_planner/fleet.hpp"

#include <algorithm>
#include <limits>
#include <utility>

namespace gd_rhcr_planner {

const char* task_state_name(uint8_t s) {
  switch (s) {
    case kQueued: return "queued";
    case kAssigned: return "assigned";
    case kPicked: return "picked";
    case kDelivered: return "delivered";
    case kFailed: return "failed";
    case kCancelled: return "cancelled";
  }
  return "unknown";
}

Fleet::Fleet(const gdrhcr::Grid& grid, const gdrhcr::DistTable& dist, int num_robots)
    : grid_(grid), dist_(dist), robots_(num_robots) {}

bool Fleet::validate_cell(int x, int y, const char* what, Cell& out, std::string& reason) const {
  const std::string where = std::string(what) + " (" + std::to_string(x) + "," + std::to_string(y) + ")";
  if (!grid_.in_bounds(x, y)) {
    reason = where + " is off the map (" + std::to_string(grid_.width()) + "x" +
             std::to_string(grid_.height()) + ")";
    return false;
  }
  out = grid_.cell(x, y);
  if (!grid_.is_free(out)) {
    reason = where + " is an obstacle";
    return false;
  }
  return true;
}

SubmitResult Fleet::submit(int px, int py, int dx, int dy, int priority, uint64_t requested_id) {
  SubmitResult r;
  if (requested_id != 0 && tasks_.count(requested_id)) {
    r.reason = "task id " + std::to_string(requested_id) + " is already in use";
    return r;  // not recorded: the id belongs to the existing task
  }
  TaskRecord t;
  t.id = requested_id;
  if (!requested_id) {  // fresh ids count up from 1, skipping ids chosen by clients
    while (tasks_.count(next_id_)) ++next_id_;
    t.id = next_id_++;
  }
  t.pickup_x = px, t.pickup_y = py, t.delivery_x = dx, t.delivery_y = dy;
  t.priority = priority;
  std::string reason;
  bool ok = validate_cell(px, py, "pickup", t.pickup, reason) &&
            validate_cell(dx, dy, "delivery", t.delivery, reason);
  if (ok && t.pickup == t.delivery) {
    ok = false;
    reason = "pickup and delivery are the same cell";
  }
  if (ok && dist_.get(t.delivery, t.pickup) >= gdrhcr::kUnreachable) {
    ok = false;
    reason = "delivery cannot be reached from the pickup";
  }
  r.task_id = t.id;
  tasks_[t.id] = t;
  if (!ok) {
    r.reason = reason;
    set_state(tasks_[t.id], kFailed, -1, "rejected: " + reason);
    return r;
  }
  r.accepted = true;
  events_.push_back({t.id, kQueued, -1, ""});
  return r;
}

bool Fleet::cancel(uint64_t id, std::string& reason) {
  auto it = tasks_.find(id);
  if (it == tasks_.end()) {
    reason = "unknown task " + std::to_string(id);
    return false;
  }
  TaskRecord& t = it->second;
  if (task_finished(t.state)) {
    reason = std::string("task already ") + task_state_name(t.state);
    return false;
  }
  if (t.robot >= 0) robots_[t.robot].task = -1;
  set_state(t, kCancelled, t.robot, "cancelled on request");
  reason.clear();
  return true;
}

bool Fleet::update_robot(int64_t id, int x, int y, bool offline, bool moving, std::string& error,
                         double now, std::optional<std::pair<int, int>> entering, gdrhcr::Heading heading) {
  if (id < 0 || id >= num_robots()) {
    error = "unknown robot id " + std::to_string(id) + " (fleet has " + std::to_string(num_robots()) + " robots)";
    return false;
  }
  Cell c;
  if (!validate_cell(x, y, "robot cell", c, error)) {
    error = "robot " + std::to_string(id) + ": " + error;
    return false;
  }
  Cell next = gdrhcr::kNoCell;
  if (moving && entering) {
    if (!validate_cell(entering->first, entering->second, "entering cell", next, error)) {
      error = "robot " + std::to_string(id) + ": " + error;
      return false;
    }
    if (!grid_.step_allowed(c, next) || next == c) {
      error = "robot " + std::to_string(id) + ": entering cell " + grid_.describe(next) + " is not next to its cell " +
              grid_.describe(c);
      return false;
    }
  }
  RobotRecord& r = robots_[id];
  r.entering = next;
  r.reported = true;
  r.cell = c;
  r.reported_offline = offline;
  r.silent = false;
  r.offline = offline || r.stuck;
  r.moving = moving;
  r.heading = heading;
  r.last_report = now;
  return true;
}

void Fleet::set_stuck(int r, bool stuck) {
  RobotRecord& rec = robots_[r];
  rec.stuck = stuck;
  rec.offline = rec.reported_offline || rec.silent || stuck;
}

std::vector<int> Fleet::mark_silent(double now, double timeout) {
  std::vector<int> fresh;
  for (int i = 0; i < num_robots(); ++i) {
    RobotRecord& r = robots_[i];
    if (!r.reported || r.silent || now - r.last_report <= timeout) continue;
    r.silent = true;
    r.offline = true;
    fresh.push_back(i);
  }
  return fresh;
}

int Fleet::offline_count() const {
  int n = 0;
  for (auto& r : robots_) n += r.offline;
  return n;
}

bool Fleet::all_reported() const { return missing_robots() == 0; }

int Fleet::missing_robots() const {
  int n = 0;
  for (auto& r : robots_) n += !r.reported;
  return n;
}

std::string Fleet::position_conflict() const {
  std::map<Cell, int> at;
  for (int i = 0; i < num_robots(); ++i) {
    auto [it, fresh] = at.emplace(robots_[i].cell, i);
    if (!fresh)
      return "robots " + std::to_string(it->second) + " and " + std::to_string(i) + " both report cell " +
             grid_.describe(robots_[i].cell);
  }
  return "";
}

void Fleet::set_state(TaskRecord& t, uint8_t s, int robot, const std::string& reason) {
  t.state = s;
  t.robot = robot;
  t.reason = reason;
  events_.push_back({t.id, s, robot, reason});
  if (s == kDelivered) ++delivered_;
  if (s == kFailed) ++failed_;
  if (task_finished(s)) {
    finished_order_.push_back(t.id);
    forget_old_finished();
  }
}

void Fleet::forget_old_finished() {
  if (finished_order_.size() <= finished_limit_) return;
  const size_t drop = finished_order_.size() - finished_limit_;
  for (size_t i = 0; i < drop; ++i) tasks_.erase(finished_order_[i]);
  finished_order_.erase(finished_order_.begin(), finished_order_.begin() + drop);
}

void Fleet::set_accepted_cells(std::vector<Cell> cells) {
  accepted_ = std::move(cells);
  accepted_.resize(robots_.size(), gdrhcr::kNoCell);
}

bool Fleet::at_cell(int r, Cell c) const {
  return robots_[r].cell == c && (accepted_.empty() || accepted_[r] == c);
}

void Fleet::advance() {
  // Cells where offline robots stand: a pickup there cannot be reached until they leave.
  std::map<Cell, int> offline_at;
  for (int r = 0; r < num_robots(); ++r)
    if (robots_[r].reported && robots_[r].offline) offline_at.emplace(robots_[r].cell, r);
  auto blocker = [&](Cell c) {
    auto it = offline_at.find(c);
    return it == offline_at.end() ? -1 : it->second;
  };
  // Transitions of the robots' tasks.
  for (int r = 0; r < num_robots(); ++r) {
    RobotRecord& rob = robots_[r];
    if (rob.task < 0) continue;
    auto it = tasks_.find(static_cast<uint64_t>(rob.task));
    if (it == tasks_.end() || task_finished(it->second.state)) {
      rob.task = -1;
      continue;
    }
    TaskRecord& t = it->second;
    if (rob.offline) {
      rob.task = -1;
      const std::string why = rob.silent ? " stopped reporting"
                              : rob.stuck ? "'s reports have not fitted for too long"
                                          : " went offline";
      set_state(t, kQueued, -1,
                "robot " + std::to_string(r) + why +
                    (t.state == kPicked ? " carrying the load; requeued from the pickup" : "; requeued"));
      continue;
    }
    if (t.state == kAssigned && blocker(t.pickup) >= 0) {  // its pickup is under a dead robot
      rob.task = -1;
      set_state(t, kQueued, -1,
                "pickup " + grid_.describe(t.pickup) + " is blocked by offline robot " +
                    std::to_string(blocker(t.pickup)) + "; waiting in the queue");
      continue;
    }
    if (t.state == kAssigned && at_cell(r, t.pickup)) set_state(t, kPicked, r, "");
    if (t.state == kPicked && at_cell(r, t.delivery)) {
      set_state(t, kDelivered, r, "");
      rob.task = -1;
    }
  }
  if (!auto_assign_) return;  // an outside dispatcher assigns (apply_assignments)
  // Greedy assignment: queued tasks by priority (high first) then id, each to the nearest idle
  // online robot (shortest path distance to the pickup; ties to the lower robot id).
  std::vector<int> idle;
  for (int r = 0; r < num_robots(); ++r)
    if (robots_[r].reported && !robots_[r].offline && robots_[r].task < 0) idle.push_back(r);
  if (idle.empty()) return;
  std::vector<TaskRecord*> queued;
  for (auto& [id, t] : tasks_)
    if (t.state == kQueued && blocker(t.pickup) < 0 && blocker(t.delivery) < 0) queued.push_back(&t);
  std::stable_sort(queued.begin(), queued.end(),
                   [](const TaskRecord* a, const TaskRecord* b) { return a->priority > b->priority; });
  for (TaskRecord* t : queued) {
    if (idle.empty()) break;
    auto row = dist_.row(t->pickup);
    int best = -1, best_d = gdrhcr::kUnreachable;
    for (size_t k = 0; k < idle.size(); ++k) {
      const int d = (*row)[robots_[idle[k]].cell];
      if (d < best_d) best_d = d, best = static_cast<int>(k);
    }
    if (best < 0) continue;  // no idle robot can reach it (yet)
    const int r = idle[best];
    idle.erase(idle.begin() + best);
    robots_[r].task = static_cast<int64_t>(t->id);
    set_state(*t, kAssigned, r, "");
    if (at_cell(r, t->pickup)) set_state(*t, kPicked, r, "");
  }
}

std::vector<std::string> Fleet::apply_assignments(const std::vector<Reassignment>& batch) {
  std::vector<std::string> refused;
  std::vector<std::pair<TaskRecord*, int>> moves;  // task, its robot before the batch
  for (const Reassignment& a : batch) {
    auto it = tasks_.find(a.task);
    const std::string what = "task " + std::to_string(a.task);
    if (it == tasks_.end() || !(it->second.state == kQueued || it->second.state == kAssigned)) {
      refused.push_back(what + " is not queued or waiting for its pickup");
      continue;
    }
    if (a.robot >= num_robots()) {
      refused.push_back(what + ": unknown robot " + std::to_string(a.robot));
      continue;
    }
    TaskRecord& t = it->second;
    const int before = t.state == kAssigned ? t.robot : -1;
    if (before >= 0 && robots_[before].task == static_cast<int64_t>(t.id)) robots_[before].task = -1;
    moves.emplace_back(&t, before);
  }
  for (size_t i = 0; i < moves.size(); ++i) {
    TaskRecord& t = *moves[i].first;
    const int before = moves[i].second;
    int r = -1;
    for (const Reassignment& a : batch)
      if (a.task == t.id) r = a.robot;
    const bool fits = r >= 0 && robots_[r].reported && !robots_[r].offline && robots_[r].task < 0;
    if (r >= 0 && !fits) refused.push_back("task " + std::to_string(t.id) + ": robot " + std::to_string(r) + " is not free");
    if (r >= 0 && !fits) r = before >= 0 && robots_[before].task < 0 && !robots_[before].offline ? before : -1;
    if (r == before && r >= 0) {  // stays where it was
      robots_[r].task = static_cast<int64_t>(t.id);
      continue;
    }
    if (r < 0) {
      if (before >= 0) set_state(t, kQueued, -1, "moved off robot " + std::to_string(before) + "; waiting for a nearer robot");
      continue;
    }
    robots_[r].task = static_cast<int64_t>(t.id);
    set_state(t, kAssigned, r, before >= 0 ? "reassigned from robot " + std::to_string(before) : "");
    if (at_cell(r, t.pickup)) set_state(t, kPicked, r, "");
  }
  return refused;
}

uint8_t Fleet::mode(int r) const { return robots_[r].offline ? kOffline : command_mode(r); }

uint8_t Fleet::command_mode(int r) const {
  const RobotRecord& rob = robots_[r];
  if (rob.task < 0) return kIdle;
  auto it = tasks_.find(static_cast<uint64_t>(rob.task));
  if (it == tasks_.end()) return kIdle;
  return it->second.state == kPicked ? kToDelivery : kToPickup;
}

void Fleet::fill_goals(std::vector<std::vector<Cell>>& goals) const {
  goals.resize(robots_.size());
  for (int r = 0; r < num_robots(); ++r) {
    auto& g = goals[r];
    g.clear();
    const RobotRecord& rob = robots_[r];
    const uint8_t m = mode(r);
    if (m == kToPickup || m == kToDelivery) {
      const TaskRecord& t = tasks_.at(static_cast<uint64_t>(rob.task));
      if (m == kToPickup) g.push_back(t.pickup);
      g.push_back(t.delivery);
    } else {
      g.push_back(rob.cell);
    }
  }
}

void Fleet::fill_positions(std::vector<Cell>& positions) const {
  positions.resize(robots_.size());
  for (int r = 0; r < num_robots(); ++r) positions[r] = robots_[r].cell;
}

std::vector<TaskEvent> Fleet::take_events() {
  std::vector<TaskEvent> out;
  out.swap(events_);
  return out;
}

const TaskRecord* Fleet::task(uint64_t id) const {
  auto it = tasks_.find(id);
  return it == tasks_.end() ? nullptr : &it->second;
}

int Fleet::distance_left(uint64_t id) const {
  const TaskRecord* t = task(id);
  if (!t || task_finished(t->state)) return -1;
  const int leg = dist_.get(t->delivery, t->pickup);
  if (t->state == kQueued || t->robot < 0 || !robots_[t->robot].reported) return leg;
  const Cell at = robots_[t->robot].cell;
  if (t->state == kAssigned) return dist_.get(t->pickup, at) + leg;
  return dist_.get(t->delivery, at);
}

std::vector<TaskRecord> Fleet::open_tasks() const {
  std::vector<TaskRecord> out;
  for (auto& [id, t] : tasks_)
    if (!task_finished(t.state)) out.push_back(t);
  return out;
}

size_t Fleet::restore(const std::vector<TaskRecord>& open, uint64_t delivered, uint64_t failed,
                      uint64_t next_id) {
  delivered_ = delivered;
  failed_ = failed;
  next_id_ = std::max(next_id_, next_id);
  size_t restored = 0;
  for (const TaskRecord& saved : open) {
    if (saved.id == 0 || tasks_.count(saved.id)) continue;  // duplicate in a damaged store
    TaskRecord t;
    t.id = saved.id;
    t.pickup_x = saved.pickup_x, t.pickup_y = saved.pickup_y;
    t.delivery_x = saved.delivery_x, t.delivery_y = saved.delivery_y;
    t.priority = saved.priority;
    next_id_ = std::max(next_id_, t.id + 1);
    std::string reason;
    const bool ok = validate_cell(t.pickup_x, t.pickup_y, "pickup", t.pickup, reason) &&
                    validate_cell(t.delivery_x, t.delivery_y, "delivery", t.delivery, reason) &&
                    t.pickup != t.delivery && dist_.get(t.delivery, t.pickup) < gdrhcr::kUnreachable;
    tasks_[t.id] = t;
    TaskRecord& rec = tasks_[t.id];
    if (!ok) {
      set_state(rec, kFailed, -1, "restored task no longer valid on this map: " +
                                      (reason.empty() ? std::string("delivery unreachable") : reason));
      continue;
    }
    ++restored;
    const int r = saved.robot;
    const bool keeps_robot = (saved.state == kAssigned || saved.state == kPicked) && r >= 0 &&
                             r < num_robots() && robots_[r].task < 0;
    if (keeps_robot) {
      robots_[r].task = static_cast<int64_t>(t.id);
      set_state(rec, saved.state, r, "restored");
    } else {
      set_state(rec, kQueued, -1, "restored");
    }
  }
  return restored;
}

size_t Fleet::count_in_state(uint8_t s) const {
  size_t n = 0;
  for (auto& [id, t] : tasks_) n += t.state == s;
  return n;
}

int hold_cascade(const gdrhcr::Grid& grid, const std::vector<Cell>& pos, std::vector<Cell>& next,
                 std::vector<uint8_t>& held, const std::vector<Cell>& blocked) {
  const int n = static_cast<int>(pos.size());
  std::map<Cell, int> entering;  // cell -> robot planned to move into it
  for (int i = 0; i < n; ++i)
    if (next[i] != pos[i]) entering[next[i]] = i;
  for (Cell c : blocked) {
    auto it = entering.find(c);
    if (it != entering.end()) held[it->second] = 1;
  }
  std::vector<int> stack;
  for (int i = 0; i < n; ++i)
    if (held[i]) {
      next[i] = pos[i];
      stack.push_back(i);
    }
  int count = static_cast<int>(stack.size());
  while (!stack.empty()) {
    const int h = stack.back();
    stack.pop_back();
    auto it = entering.find(pos[h]);
    if (it == entering.end()) continue;
    const int r = it->second;
    entering.erase(it);
    if (held[r]) continue;
    held[r] = 1;
    next[r] = pos[r];
    ++count;
    stack.push_back(r);
  }
  (void)grid;
  return count;
}

}  // namespace gd_rhcr_planner
