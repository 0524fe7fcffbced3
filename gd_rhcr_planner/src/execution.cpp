// Execution layer: Action Dependency Graph over a rolling horizon (Hönig et al., RA-L 2019).
// See include/gd_rhcr_planner/execution.hpp.
#include "gd_rhcr_planner/execution.hpp"

#include <algorithm>
#include <iterator>

#include "gdrhcr/params.hpp"

namespace gd_rhcr_planner {

using gdrhcr::Heading;
using gdrhcr::kNoCell;
using gdrhcr::kNoHeading;
using gdrhcr::Pose;

namespace {

// Robot r is on hold in the flags of the current call (tick or advance).
bool on_hold(const std::vector<uint8_t>& hold, int r) { return r < static_cast<int>(hold.size()) && hold[r]; }

std::string who(int r) { return "robot " + std::to_string(r); }

bool valid_heading(Heading h) { return h >= 0 && h < gdrhcr::kNumHeadings; }

// The caller's flags, or none.
const std::vector<uint8_t>& hold_flags(const std::vector<uint8_t>* hold) {
  static const std::vector<uint8_t> kNone;
  return hold ? *hold : kNone;
}

}  // namespace

const char* robot_health_name(RobotHealth h) {
  switch (h) {
    case RobotHealth::kOk: return "ok";
    case RobotHealth::kMissing: return "missing";
    case RobotHealth::kOffline: return "offline";
    case RobotHealth::kSilent: return "silent";
    case RobotHealth::kInconsistent: return "inconsistent";
  }
  return "unknown";
}

Executor::Executor(const gdrhcr::Grid& grid, const gdrhcr::DistTable& dist, int num_robots, ExecutorConfig cfg)
    : grid_(grid), dist_(dist), cfg_(cfg), tracks_(num_robots), agent_of_robot_(num_robots, -1),
      validator_(grid, cfg.action_model) {
  if (cfg_.commit_horizon < 1) throw gdrhcr::ParamError("~commit_horizon must be >= 1");
  if (dist.action_model() != cfg_.action_model)
    throw gdrhcr::ParamError(std::string("executor: the distance table is in the ") +
                             gdrhcr::action_model_name(dist.action_model()) + " action model, the robots in " +
                             gdrhcr::action_model_name(cfg_.action_model));
}

std::vector<Cell> Executor::committed(int r) const {
  std::vector<Cell> cells;
  for (const Pose& p : tracks_[r].path) cells.push_back(p.cell);
  return cells;
}

std::vector<Pose> Executor::committed_poses(int r) const {
  return std::vector<Pose>(tracks_[r].path.begin(), tracks_[r].path.end());
}

// The robot other than `except` that is in c, is entering c, or claims c; -1 when none.
int Executor::holder_of(Cell c, int except) const {
  for (int q = 0; q < num_robots(); ++q) {
    if (q == except) continue;
    const Track& t = tracks_[q];
    if (t.claimed == c) return q;
    if (!t.active) continue;
    if (t.cell == c || (t.dispatched && t.path.front().cell == c)) return q;
    if (t.unknown_move)
      for (Cell nb : grid_.neighbours(t.cell))
        if (nb == c) return q;
  }
  return -1;
}

// Cells a bad robot may be in besides its known cell: the cell it was commanded into (it may be
// on its way), the cell it claims, or every neighbour when it moves without a command.
void Executor::add_blocked_cells(int r, std::vector<Cell>& blocked) const {
  const Track& t = tracks_[r];
  if (t.dispatched) blocked.push_back(t.path.front().cell);
  if (t.claimed != kNoCell) blocked.push_back(t.claimed);
  if (t.unknown_move)
    for (Cell nb : grid_.neighbours(t.cell)) blocked.push_back(nb);
}

void Executor::reconcile(const std::vector<RobotRecord>& robots, TickOutput& out) {
  bool need_resync = false;
  for (int r = 0; r < num_robots(); ++r) {
    const RobotRecord& rec = robots[r];
    if (!rec.reported) continue;  // missing: stays out
    tracks_[r].reported_moving = rec.moving;
    if (!tracks_[r].active) need_resync |= place(r, rec, out);  // its first report, or it could not be placed before
    else if (rec.silent) need_resync |= fall_silent(r, out);
    else need_resync |= take_report(r, robots, out);
  }
  if (need_resync) {
    resync();
    ++out.resyncs;
  }
}

// A robot not placed yet reports: it is placed at its cell unless another robot holds that cell
// (then it stays out, inconsistent, and the cell it claims is blocked). True when placed.
bool Executor::place(int r, const RobotRecord& rec, TickOutput& out) {
  Track& t = tracks_[r];
  if (rec.silent) return false;
  const Cell x = rec.cell;
  const int other = holder_of(x, r);
  if (other >= 0) {
    if (t.health != RobotHealth::kInconsistent || t.claimed != x)
      out.warnings.push_back(who(r) + " reports cell " + grid_.describe(x) + ", which robot " +
                             std::to_string(other) + " holds: not planned (an obstacle there) until it reports a free cell");
    t.health = RobotHealth::kInconsistent;
    t.claimed = x;
    return false;
  }
  t = Track{};
  t.reported_moving = rec.moving;
  t.active = true;
  t.cell = x;
  t.heading = rec.heading;
  if (rotation() && !valid_heading(t.heading)) t.heading = gdrhcr::kEast;  // an obstacle (report_health) facing any way
  t.unknown_move = rec.moving && rec.entering == kNoCell;  // known: only that cell is blocked
  if (rec.moving) t.claimed = rec.entering;
  t.health = rec.moving ? RobotHealth::kInconsistent : report_health(r, rec, out);
  if (rec.moving) out.warnings.push_back(who(r) + " first reports while moving: an obstacle until it stops");
  if (agent_of_robot_[r] < 0) {  // its planner agent index, for good
    agent_of_robot_[r] = static_cast<int>(robot_of_agent_.size());
    robot_of_agent_.push_back(r);
  }
  return true;
}

// No news from a placed robot: it stays where we know it is, and what it may be entering stays
// held. True when it just fell silent.
bool Executor::fall_silent(int r, TickOutput& out) {
  Track& t = tracks_[r];
  if (t.health == RobotHealth::kSilent) return false;
  out.warnings.push_back(who(r) + " is silent: an obstacle at " + grid_.describe(t.cell) +
                         (t.dispatched ? " and " + grid_.describe(t.path.front().cell) : std::string()));
  t.health = RobotHealth::kSilent;
  return true;
}

// A placed robot's report: at rest or moving in its cell, arrived in its dispatched cell, or in a
// cell it was not commanded into; then its health. True when the commitments need a resync.
bool Executor::take_report(int r, const std::vector<RobotRecord>& robots, TickOutput& out) {
  Track& t = tracks_[r];
  const RobotRecord& rec = robots[r];
  const Cell x = rec.cell;
  bool need_resync = false;
  RobotHealth h = report_health(r, rec, out);
  if (!rotation()) t.heading = rec.heading;  // mapf: the robot's own (commands turn it before a move)
  if (x == t.cell) {
    if (!rec.moving || rec.entering != t.claimed) t.claimed = kNoCell;
    if (t.dispatched && rec.reported_offline && !rec.moving) {  // OFFLINE at rest: it will not make the move
      t.dispatched = false;
      t.path.clear();
      need_resync = true;
    } else if (rotation() && h == RobotHealth::kOk) {
      need_resync |= take_heading(r, rec, out);
    }
  } else if (t.dispatched && x == t.path.front().cell) {
    arrive(r);
    if (rotation() && h == RobotHealth::kOk) need_resync |= take_heading(r, rec, out);
  } else if (take_unexpected_cell(r, x, robots, out)) {
    need_resync = true;
  } else {
    h = RobotHealth::kInconsistent;
  }
  if (x == t.cell && rec.moving && rec.entering != kNoCell && !(t.dispatched && rec.entering == t.path.front().cell)) {
    need_resync |= take_entering(r, rec.entering, robots, out);
    h = RobotHealth::kInconsistent;
  }
  const bool unknown = rec.moving && !t.dispatched && rec.entering == kNoCell;
  if (unknown && !t.unknown_move)
    out.warnings.push_back(who(r) + " is moving without a command: an obstacle around " + grid_.describe(t.cell));
  if (unknown != t.unknown_move) need_resync = true;
  t.unknown_move = unknown;
  if (unknown) h = RobotHealth::kInconsistent;
  return set_health(r, h, out) || need_resync;
}

// The health a placed robot's report gives it: offline when it says so; in the rotation model a
// report without a heading makes it inconsistent (an obstacle: it cannot be planned).
RobotHealth Executor::report_health(int r, const RobotRecord& rec, TickOutput& out) const {
  if (rec.reported_offline) return RobotHealth::kOffline;
  if (rotation() && !valid_heading(rec.heading)) {
    if (tracks_[r].health != RobotHealth::kInconsistent)
      out.warnings.push_back(who(r) + " reports no heading, which the rotation action model needs: an obstacle at " +
                             grid_.describe(rec.cell));
    return RobotHealth::kInconsistent;
  }
  return RobotHealth::kOk;
}

// Rotation model: robot r reports its known cell (or just arrived in its dispatched one) with
// heading rec.heading. Its dispatched turn is done when that is the turn's heading at rest; any
// other new heading (a turn nobody commanded, or a forward move that ended turned) is believed:
// its commitments not under way are dropped and it is replanned from there (true: resync).
bool Executor::take_heading(int r, const RobotRecord& rec, TickOutput& out) {
  Track& t = tracks_[r];
  if (rec.heading == t.heading) return false;
  const bool turning = t.dispatched && t.path.front().cell == t.cell;
  if (turning && rec.heading == t.path.front().heading && !rec.moving) {
    arrive(r);
    return false;
  }
  if (rec.moving) return false;  // on its way into its dispatched cell: judged on arrival
  out.warnings.push_back(who(r) + " reports heading " + gdrhcr::heading_name(rec.heading) + " in " +
                         grid_.describe(t.cell) + ", not the one it was commanded (" +
                         gdrhcr::heading_name(turning ? t.path.front().heading : t.heading) + "): replanned from there");
  t.heading = rec.heading;
  t.dispatched = false;  // at rest in its cell: a forward move it no longer faces is not made
  t.path.clear();
  return true;
}

// Robot r reports cell x, which it was not commanded into. A slip (it ended in a free neighbour of
// the cell it was in or was sent to) is taken as the truth (true: replanned from there), also when another robot
// was only commanded into x and still reports at rest where it was: that robot's move is taken
// back (told to stay). A cell another robot is in or entering, or a jump, is not believed (false):
// the robot is an obstacle at both cells until it reports a cell that fits (it may then be x,
// once x is free).
bool Executor::take_unexpected_cell(int r, Cell x, const std::vector<RobotRecord>& robots, TickOutput& out) {
  Track& t = tracks_[r];
  // One move from where it was, or from the cell it was sent to (it arrived, unreported, and slipped).
  const bool reachable =
      grid_.step_allowed(t.cell, x) || (t.dispatched && grid_.step_allowed(t.path.front().cell, x));
  bool withdrawn = false;
  const int other = reachable ? yield_cell(r, x, robots, "slipped into it", out, withdrawn) : holder_of(x, r);
  if (other < 0 && reachable) {
    out.warnings.push_back(who(r) + " reports " + grid_.describe(x) + ", not the cell it was commanded (" +
                           grid_.describe(t.dispatched ? t.path.front().cell : t.cell) + "): replanned from there");
    t.cell = x;
    if (!rotation() || valid_heading(robots[r].heading)) t.heading = robots[r].heading;
    t.dispatched = false;
    t.path.clear();
    t.claimed = kNoCell;
    return true;
  }
  if (t.claimed != x)
    out.warnings.push_back(who(r) + " reports cell " + grid_.describe(x) +
                           (other >= 0 ? ", which robot " + std::to_string(other) + " holds"
                                       : std::string(", more than one move from where it was")) +
                           ": an obstacle at " + grid_.describe(t.cell) + " and " + grid_.describe(x));
  t.claimed = x;
  return false;
}

// Robot r, still in its cell, reports moving into x, a neighbour it was not commanded into (a slip
// under way): it is an obstacle at its cell and at x (claimed) until it reports where it ended, so
// nobody is sent into x meanwhile. A robot commanded into x that has not left its own cell has that
// move taken back (true: the commitments need a resync).
bool Executor::take_entering(int r, Cell x, const std::vector<RobotRecord>& robots, TickOutput& out) {
  Track& t = tracks_[r];
  if (t.claimed == x) return false;
  bool withdrawn = false;
  const int other = yield_cell(r, x, robots, "is moving into it", out, withdrawn);
  out.warnings.push_back(who(r) + " is moving into " + grid_.describe(x) + ", not the cell it was commanded (" +
                         grid_.describe(t.dispatched ? t.path.front().cell : t.cell) + ")" +
                         (other >= 0 ? ", which robot " + std::to_string(other) + " holds" : std::string()) +
                         ": an obstacle at both cells until it stops");
  t.claimed = x;
  return withdrawn;
}

// The robot other than r that holds x (-1: none), after taking back, for r, a move into x that its
// robot has not started (withdraw_move; warned with what r did, `how`; `withdrawn` set).
int Executor::yield_cell(int r, Cell x, const std::vector<RobotRecord>& robots, const char* how, TickOutput& out,
                         bool& withdrawn) {
  const int other = holder_of(x, r);
  if (other < 0 || !withdraw_move(other, x, r, robots)) return other;
  out.warnings.push_back(who(other) + "'s move into " + grid_.describe(x) + " is taken back: " + who(r) + " " + how);
  withdrawn = true;
  return -1;
}

// Robot q was commanded into x but reports at rest in its own cell, which it has not left, and no
// robot but q holds x (r, who reports x, aside): q's move is taken back (true; the caller resyncs
// the commitments).
bool Executor::withdraw_move(int q, Cell x, int r, const std::vector<RobotRecord>& robots) {
  Track& t = tracks_[q];
  const RobotRecord& rec = robots[q];
  if (!t.active || t.health != RobotHealth::kOk || !t.dispatched || t.path.front().cell != x || t.cell == x ||
      t.claimed == x || !rec.reported || rec.silent || rec.moving || rec.cell != t.cell)
    return false;
  t.dispatched = false;  // does anybody else hold x?
  if (holder_of(x, r) >= 0) {
    t.dispatched = true;
    return false;
  }
  t.path.clear();
  return true;
}

// Robot r's health becomes h (warned when it changes). True when it changed.
bool Executor::set_health(int r, RobotHealth h, TickOutput& out) {
  Track& t = tracks_[r];
  if (h == t.health) return false;
  if (h == RobotHealth::kOffline)
    out.warnings.push_back(who(r) + " is offline: an obstacle at " + grid_.describe(t.cell));
  else if (h == RobotHealth::kOk)
    out.warnings.push_back(who(r) + " is back (" + robot_health_name(t.health) + " before)");
  t.health = h;
  return true;
}

// Robot r reports arrival in its dispatched cell: it has left its cell, which the next robot in
// that cell's queue may now enter. A turn done leaves the robot in its cell (first in its queue).
void Executor::arrive(int r) {
  Track& t = tracks_[r];
  const Pose p = t.path.front();
  auto it = p.cell != t.cell ? visits_.find(t.cell) : visits_.end();
  if (it != visits_.end()) {
    auto pos = std::find(it->second.begin(), it->second.end(), r);
    if (pos != it->second.end()) it->second.erase(pos);
    if (it->second.empty()) visits_.erase(it);
  }
  t.cell = p.cell;
  t.heading = p.heading;
  t.path.pop_front();
  t.dispatched = false;
  t.claimed = kNoCell;
}

// Cells robots report being in, or may be entering, that the executor has not accounted for yet (a
// slip, a robot not placed, a move without a command): nobody is sent into them between ticks; the
// next tick reconciles the reports.
std::vector<Cell> Executor::unaccounted_cells(const std::vector<RobotRecord>& robots) const {
  std::vector<Cell> cells;
  for (int r = 0; r < num_robots(); ++r) {
    const Track& t = tracks_[r];
    const RobotRecord& rec = robots[r];
    if (!rec.reported || rec.silent || rec.cell == kNoCell) continue;
    const bool known = t.active && (rec.cell == t.cell || (t.dispatched && rec.cell == t.path.front().cell));
    if (!known) cells.push_back(rec.cell);
    if (rec.moving && rec.entering != kNoCell) {
      if (!(t.active && t.dispatched && rec.entering == t.path.front().cell)) cells.push_back(rec.entering);
    } else if (rec.moving && !(t.active && t.dispatched)) {
      for (Cell nb : grid_.neighbours(rec.cell)) cells.push_back(nb);
    }
  }
  std::sort(cells.begin(), cells.end());
  return cells;
}

std::vector<int> Executor::advance(const std::vector<RobotRecord>& robots, const std::vector<uint8_t>* hold) {
  std::vector<int> changed;
  if (static_cast<int>(robots.size()) != num_robots()) return changed;
  const std::vector<Cell> avoid = unaccounted_cells(robots);
  bool arrived = false;
  for (int r = 0; r < num_robots(); ++r) {
    Track& t = tracks_[r];
    const RobotRecord& rec = robots[r];
    if (!t.active || t.health != RobotHealth::kOk || !t.dispatched || !rec.reported || rec.silent ||
        rec.reported_offline || rec.moving || rec.cell != t.path.front().cell)
      continue;
    if (t.path.front().cell == t.cell && rec.heading != t.path.front().heading) continue;  // still turning
    arrive(r);
    t.reported_moving = false;
    arrived = true;
  }
  if (!arrived) return changed;
  TickOutput unused;
  // A move dispatched between ticks counts as dispatched in the coming tick: it is late only if
  // it is not made by the tick after.
  dispatch_ready(unused, ticks_ + 1, hold_flags(hold), &changed, &avoid);
  return changed;
}

Cell Executor::command(int r) const {
  const Track& t = tracks_[r];
  if (t.health == RobotHealth::kInconsistent) {
    // Told to stay where it reports; a robot moving where we cannot tell gets no command (it stops
    // at the end of its move, and its next report is judged), unless it is making its own move.
    if (t.reported_moving) return t.dispatched && t.claimed == kNoCell ? t.path.front().cell : kNoCell;
    return t.claimed != kNoCell ? t.claimed : t.cell;
  }
  return t.dispatched ? t.path.front().cell : t.cell;
}

Heading Executor::command_heading(int r) const {
  const Track& t = tracks_[r];
  const Cell c = command(r);
  if (t.dispatched && !t.path.empty() && c == t.path.front().cell) return t.path.front().heading;
  if (!rotation() && t.health == RobotHealth::kOk && c == t.cell && !t.path.empty() && t.heading != kNoHeading)
    return t.path.front().heading;  // waits for its next move: turns towards it meanwhile
  return t.heading;
}

gdrhcr::Action command_action(Pose known, Cell cell, Heading heading) {
  if (cell != known.cell) return gdrhcr::Action::kForward;
  if (heading == kNoHeading || known.heading == kNoHeading || heading == known.heading) return gdrhcr::Action::kWait;
  return ((heading - known.heading) & 3) == 3 ? gdrhcr::Action::kCounterClockwise : gdrhcr::Action::kClockwise;
}

std::vector<Cell> Executor::accepted_cells() const {
  std::vector<Cell> cells(tracks_.size(), kNoCell);
  for (size_t r = 0; r < tracks_.size(); ++r)
    if (tracks_[r].active) cells[r] = tracks_[r].cell;
  return cells;
}

// Drops robot r's commitments that were not dispatched yet, and, transitively, those of every
// robot queued to enter the cell r now ends in after r: it would wait there for a move of r that
// is no longer planned (and the planner would see both robots in that cell).
int Executor::revoke(int r) {
  Track& t = tracks_[r];
  const size_t keep = t.dispatched ? 1 : 0;
  if (t.path.size() <= keep) return 0;
  t.revoked = ticks_;
  for (size_t k = t.path.size(); k-- > keep;) {  // r's last visit of each dropped cell goes
    if (t.path[k].cell == (k == 0 ? t.cell : t.path[k - 1].cell)) continue;  // a turn: no visit
    auto it = visits_.find(t.path[k].cell);
    if (it == visits_.end()) continue;  // never: every committed cell has r's visit queued
    auto& q = it->second;
    auto pos = std::find(q.rbegin(), q.rend(), r);
    if (pos != q.rend()) q.erase(std::prev(pos.base()));
    if (q.empty()) visits_.erase(it);
  }
  t.path.resize(keep);
  const Cell end = keep ? t.path.front().cell : t.cell;
  std::vector<int> behind;
  auto it = visits_.find(end);
  if (it != visits_.end()) {
    auto last = std::find(it->second.rbegin(), it->second.rend(), r).base();  // after r's last visit
    behind.assign(last, it->second.end());
  }
  int n = 1;
  for (int q : behind) n += revoke(q);
  return n;
}

// A late robot's undispatched moves, and the moves of the robots waiting to enter the cell it
// has not left yet, are taken back (transitively, see revoke): they are planned again this tick,
// around it, instead of queueing behind it for as long as it is late.
int Executor::revoke_behind_late() {
  int n = 0;
  for (int r = 0; r < num_robots(); ++r) {
    const Track& t = tracks_[r];
    if (!t.active || t.health != RobotHealth::kOk || !late(t)) continue;
    n += revoke(r);
    auto it = visits_.find(t.cell);
    if (it == visits_.end()) continue;
    const std::vector<int> waiting(it->second.begin() + 1, it->second.end());
    for (int q : waiting)
      if (!tracks_[q].dispatched) n += revoke(q);
  }
  return n;
}

// Drops every commitment that was not dispatched yet and rebuilds the cells' visit queues from
// what robots are in and what they were commanded into.
void Executor::resync() {
  ++resyncs_total_;
  visits_.clear();
  for (int r = 0; r < num_robots(); ++r) {
    Track& t = tracks_[r];
    if (!t.active) continue;
    if (t.dispatched) t.path.resize(1);
    else t.path.clear();
    visits_[t.cell].push_back(r);
  }
  for (int r = 0; r < num_robots(); ++r) {
    const Track& t = tracks_[r];
    if (t.active && t.dispatched && t.path.front().cell != t.cell) visits_[t.path.front().cell].push_back(r);
  }
}

int Executor::dispatch_ready(TickOutput& out, uint64_t stamp, const std::vector<uint8_t>& hold,
                             std::vector<int>* sent, const std::vector<Cell>* avoid) {
  int n = 0;
  for (int r = 0; r < num_robots(); ++r) {
    Track& t = tracks_[r];
    if (!t.active || t.health != RobotHealth::kOk || t.dispatched || t.path.empty() || on_hold(hold, r)) continue;
    if (avoid && std::binary_search(avoid->begin(), avoid->end(), t.path.front().cell)) continue;
    auto it = visits_.find(t.path.front().cell);  // a turn: r's own cell, where r is first
    if (it != visits_.end() && !it->second.empty() && it->second.front() == r) {
      t.dispatched = true;
      t.dispatched_at = stamp;
      if (sent) sent->push_back(r);
      ++n;
    }
  }
  out.dispatched += n;
  return n;
}

const gdrhcr::DistTable& Executor::dist_for(const std::vector<Cell>& obstacles) {
  if (obstacles != obstacle_cells_) {
    obstacle_cells_ = obstacles;
    obstacle_dist_.reset();
    if (!obstacles.empty())
      obstacle_dist_ =
          std::make_shared<const gdrhcr::DistTable>(grid_, obstacles, cfg_.action_model, cfg_.dist_budget_bytes,
                                                    dist_.step_costs());
  }
  return obstacle_dist_ ? *obstacle_dist_ : dist_;
}

// The goals the planner gets for robot r from its committed end state: goals its committed path
// already passes are dropped (the fleet marks them reached when the robot gets there); an idle
// robot (its goal is its own cell) is to stay at its end state.
std::vector<Cell> Executor::planner_goals(int r, const std::vector<Cell>& fleet_goals, Cell end) const {
  const Track& t = tracks_[r];
  if (fleet_goals.empty() || (fleet_goals.size() == 1 && fleet_goals[0] == t.cell)) return {end};
  size_t k = 0;
  for (const Pose& p : t.path)
    if (k + 1 < fleet_goals.size() && p.cell == fleet_goals[k]) ++k;
  return std::vector<Cell>(fleet_goals.begin() + k, fleet_goals.end());
}

int hold_rotations(const std::vector<Cell>& pos, std::vector<Cell>& next, std::vector<uint8_t>& held) {
  const int n = static_cast<int>(pos.size());
  std::unordered_map<Cell, int> at;
  at.reserve(n * 2);
  for (int i = 0; i < n; ++i) at[pos[i]] = i;
  // succ[i]: the mover whose cell mover i enters (i follows it), else -1.
  std::vector<int> succ(n, -1);
  for (int i = 0; i < n; ++i) {
    if (next[i] == pos[i]) continue;
    auto it = at.find(next[i]);
    if (it != at.end() && next[it->second] != pos[it->second]) succ[i] = it->second;
  }
  std::vector<uint8_t> state(n, 0);  // 0 new, 1 on the current chain, 2 done
  int count = 0;
  std::vector<int> chain;
  for (int s = 0; s < n; ++s) {
    if (state[s]) continue;
    chain.clear();
    int i = s;
    while (i >= 0 && state[i] == 0) {
      state[i] = 1;
      chain.push_back(i);
      i = succ[i];
    }
    if (i >= 0 && state[i] == 1) {  // a cycle from i to the end of the chain
      auto from = std::find(chain.begin(), chain.end(), i);
      for (auto it = from; it != chain.end(); ++it) {
        held[*it] = 1;
        next[*it] = pos[*it];
        ++count;
      }
    }
    for (int c : chain) state[c] = 2;
  }
  return count;
}

// One planned step: the planner plans one more step from the committed end states, held moves
// become waits, and the step is validated and committed.
void Executor::plan_and_commit(const std::vector<std::vector<Cell>>& goals, const std::vector<uint8_t>& hold,
                               DeadlinePlanner& planner, TickOutput& out) {
  StepInput in;
  gather_agents(goals, hold, in, out);
  if (in.positions.empty()) return;
  std::vector<Cell> next = call_planner(in, planner, out);
  commit_step(in, next, out);
}

// The planner's agents (out.robot_of_agent: the placed robots, each under the index it got when
// placed), with their positions, goals (out.agent_goals), who is immovable, and the cells to keep
// them out of.
void Executor::gather_agents(const std::vector<std::vector<Cell>>& goals, const std::vector<uint8_t>& hold,
                             StepInput& in, TickOutput& out) const {
  const std::vector<int>& robot_of = out.robot_of_agent = robot_of_agent_;
  const int na = static_cast<int>(robot_of.size());
  in.positions.assign(na, kNoCell);
  if (rotation()) in.headings.assign(na, gdrhcr::kEast);
  in.immovable.assign(na, 0);
  out.agent_goals.assign(na, {});
  for (int a = 0; a < na; ++a) {
    const int r = robot_of[a];
    const Track& t = tracks_[r];
    if (t.health != RobotHealth::kOk) {  // an obstacle at its cell, and wherever it may be entering
      in.positions[a] = t.cell;
      if (rotation()) in.headings[a] = t.heading;
      in.immovable[a] = 1;
      in.obstacles.push_back(t.cell);
      add_blocked_cells(r, in.blocked);
      out.agent_goals[a] = {t.cell};
      continue;
    }
    const Cell end = t.path.empty() ? t.cell : t.path.back().cell;
    in.positions[a] = end;
    if (rotation()) in.headings[a] = t.path.empty() ? t.heading : t.path.back().heading;
    // A robot with commit_horizon moves committed and not finished (the one it is making
    // included: a robot still on its way at the next tick is late) gets no further move in
    // this step; the others plan around its end state, so no commitments pile up behind a
    // late robot.
    in.immovable[a] = static_cast<int>(t.path.size()) >= cfg_.commit_horizon || on_hold(hold, r);
    // Cells the planner must keep everybody out of in this step, as no robot there will leave
    // it soon: a late robot's (commanded in an earlier tick, not arrived) still fills the
    // cell it leaves, and a robot waiting for its committed move fills its cell until its
    // move is dispatched and made. Behind such a robot others would only queue: the planner
    // routes them around (WorldView::blocked), and the hold cascade still holds any move into
    // them.
    if (late(t) || (!t.dispatched && !t.path.empty())) in.late_cells.push_back(t.cell);
    out.agent_goals[a] = on_hold(hold, r) ? std::vector<Cell>{end} : planner_goals(r, goals[r], end);
  }
  for (const Track& t : tracks_)
    if (!t.active && t.claimed != kNoCell) in.blocked.push_back(t.claimed);
}

// The planner's step from the agents' positions, with a distance table around the bad robots'
// cells; `in.blocked` gets the late cells (for the hold cascade). Returns each agent's next cell.
std::vector<Cell> Executor::call_planner(StepInput& in, DeadlinePlanner& planner, TickOutput& out) {
  std::vector<Cell>& obstacles = in.obstacles;
  obstacles.insert(obstacles.end(), in.blocked.begin(), in.blocked.end());
  std::sort(obstacles.begin(), obstacles.end());
  obstacles.erase(std::unique(obstacles.begin(), obstacles.end()), obstacles.end());
  const gdrhcr::DistTable& dist = dist_for(obstacles);
  in.blocked.insert(in.blocked.end(), in.late_cells.begin(), in.late_cells.end());

  gdrhcr::WorldView world{grid_, dist, static_cast<int>(steps_), in.positions, out.agent_goals};
  if (rotation()) {
    world.action_model = cfg_.action_model;
    world.headings = &in.headings;
    in.next_headings = in.headings;
    world.next_headings = &in.next_headings;
  }
  if (std::any_of(in.immovable.begin(), in.immovable.end(), [](uint8_t v) { return v != 0; }))
    world.immovable = &in.immovable;
  // Blocked for the planner: the late and waiting robots' cells (one per robot, so no two alike)
  // no planned agent stands on (a robot committed behind a late one has its end state in the late
  // robot's cell).
  std::vector<uint8_t> is_position(grid_.num_cells(), 0);
  for (Cell c : in.positions) is_position[c] = 1;
  std::vector<Cell> planner_blocked;
  for (Cell c : in.late_cells)
    if (!is_position[c]) planner_blocked.push_back(c);
  if (!planner_blocked.empty()) world.blocked = &planner_blocked;
  std::vector<Cell> next = in.positions;
  out.outcome = planner.step(world, next, cfg_.plan_deadline_s, obstacle_dist_);
  out.planner_called = true;
  return next;
}

// Moves of immovable robots, into held or blocked cells, and around cycles become waits (a held
// robot does not turn either); a step the validator rejects (in the action model in force) becomes
// a wait for everybody (out.plan_error). The rest is committed: each robot's new pose is appended
// to its path, and a new cell to the cell's queue of visits.
void Executor::commit_step(StepInput& in, std::vector<Cell>& next, TickOutput& out) {
  const std::vector<Cell>& positions = in.positions;
  std::vector<uint8_t> held = in.immovable;
  hold_cascade(grid_, positions, next, held, in.blocked);
  if (hold_rotations(positions, next, held) > 0) hold_cascade(grid_, positions, next, held, in.blocked);
  const bool rot = rotation();
  for (size_t a = 0; rot && a < held.size(); ++a)
    if (held[a]) in.next_headings[a] = in.headings[a];
  if (auto violation = validator_.check(positions, next, rot ? &in.headings : nullptr, rot ? &in.next_headings : nullptr)) {
    out.plan_error = violation->describe(grid_, static_cast<int>(steps_));
    next = positions;
    in.next_headings = in.headings;
  }
  for (uint8_t h : held) out.held += h != 0;
  ++steps_;
  for (size_t a = 0; a < positions.size(); ++a) {
    const Pose to{next[a], rot ? in.next_headings[a] : gdrhcr::heading_of_move(grid_, positions[a], next[a])};
    if (to.cell == positions[a] && (!rot || to.heading == in.headings[a])) continue;
    const int r = out.robot_of_agent[a];
    tracks_[r].path.push_back(to);
    tracks_[r].stepped = steps_;
    if (to.cell != positions[a]) visits_[to.cell].push_back(r);
  }
}

TickOutput Executor::tick(const std::vector<RobotRecord>& robots, const std::vector<std::vector<Cell>>& goals,
                          DeadlinePlanner& planner, bool proceed_without_missing, const std::vector<uint8_t>* hold) {
  TickOutput out;
  const std::vector<uint8_t>& held = hold_flags(hold);
  ++ticks_;
  const int n = num_robots();
  if (static_cast<int>(robots.size()) != n || static_cast<int>(goals.size()) != n) {
    out.skip_reason = "executor: " + std::to_string(robots.size()) + " robot records and " +
                      std::to_string(goals.size()) + " goal lists for " + std::to_string(n) + " robots";
    return out;
  }
  int missing = 0, reported = 0;
  for (const RobotRecord& rec : robots) {
    missing += !rec.reported;
    reported += rec.reported;
  }
  if (reported == 0 || (missing > 0 && !proceed_without_missing)) {
    out.skip_reason = std::to_string(missing) + " robots have not reported a state yet";
    return out;
  }
  out.command.assign(n, kNoCell);
  out.command_heading.assign(n, kNoHeading);
  out.headings.assign(n, kNoHeading);
  out.end_state.assign(n, kNoCell);
  reconcile(robots, out);
  dispatch_ready(out, ticks_, held);
  if (cfg_.revoke_behind_late) out.revoked = revoke_behind_late();
  plan_and_commit(goals, held, planner, out);
  if (cfg_.catch_up > 0 && out.plan_error.empty() && out.planner_called && !out.outcome.fallback &&
      planner.primary_idle())
    catch_up(goals, held, planner.primary(), out);
  dispatch_ready(out, ticks_, held);
  out.stepped = true;
  out.cells.assign(n, kNoCell);
  out.health.assign(n, RobotHealth::kMissing);
  for (int r = 0; r < n; ++r) {
    const Track& t = tracks_[r];
    out.health[r] = t.health;
    if (!t.active) {
      if (t.claimed != kNoCell) out.command[r] = command(r);  // not placed: told to stay where it reports
      continue;
    }
    out.cells[r] = t.cell;
    out.headings[r] = t.heading;
    // On hold and at rest: told to stay; its commanded cell stays reserved for when it is released.
    const bool stay = on_hold(held, r) && !t.reported_moving && t.health != RobotHealth::kInconsistent;
    out.command[r] = stay ? t.cell : command(r);
    out.command_heading[r] = stay ? t.heading : command_heading(r);
    out.end_state[r] = t.path.empty() ? t.cell : t.path.back().cell;
    if (t.health == RobotHealth::kOk && !t.dispatched && !t.path.empty() && !on_hold(held, r)) ++out.waiting;
  }
  return out;
}

// Catch-up (ExecutorConfig::catch_up), after the tick's step: the robots owed steps (owe_steps)
// make one more move each, into the cell the planner means them to enter next
// (Planner::intended_next), when no robot ends its commitments there and the cell is not blocked.
// In the rotation model only a forward move is made up (the cell ahead of the robot's planned
// heading): turns are not. The ADG orders such a move like any other commitment; the planner's
// clock does not move.
void Executor::catch_up(const std::vector<std::vector<Cell>>& goals, const std::vector<uint8_t>& hold,
                        const gdrhcr::Planner& planner, TickOutput& out) {
  const std::vector<uint8_t> owing = owe_steps(hold);
  if (std::find(owing.begin(), owing.end(), 1) == owing.end()) return;
  TickOutput extra;
  StepInput in;
  gather_agents(goals, hold, in, extra);
  std::vector<uint8_t> taken(grid_.num_cells(), 0);
  for (const auto* cells : {&in.positions, &in.obstacles, &in.blocked, &in.late_cells})
    for (Cell c : *cells) taken[c] = 1;
  std::vector<Cell> next = in.positions;
  in.next_headings = in.headings;
  for (int a = 0; a < static_cast<int>(next.size()); ++a) {
    in.immovable[a] = !owing[extra.robot_of_agent[a]];
    if (in.immovable[a]) continue;
    const Cell c = planner.intended_next(a, in.positions[a]);
    if (c == kNoCell || taken[c] || !grid_.step_allowed(in.positions[a], c)) continue;
    if (rotation() && gdrhcr::heading_of_move(grid_, in.positions[a], c) != in.headings[a]) continue;
    taken[c] = 1;
    next[a] = c;
  }
  const uint64_t step = steps_;
  commit_step(in, next, extra);
  for (int r = 0; r < num_robots(); ++r)
    if (owing[r] && tracks_[r].stepped == steps_) --tracks_[r].owed, ++out.caught_up;
  steps_ = step;
  if (!extra.plan_error.empty()) out.plan_error = extra.plan_error;
}

// A robot is owed one more step for each tick it is late, its commitments are taken back behind
// a late robot, or it gets no move in the tick's step, whatever held it (a late robot ahead, a
// turn, a wait in the plan), up to catch_up. Returns, per robot, whether it makes up a step now:
// owed, not late itself, and with fewer than commit_horizon moves committed. Robots that are not
// healthy or on hold owe nothing.
std::vector<uint8_t> Executor::owe_steps(const std::vector<uint8_t>& hold) {
  const int n = num_robots();
  std::vector<uint8_t> owing(n, 0);
  for (int r = 0; r < n; ++r) {
    Track& t = tracks_[r];
    if (!t.active || t.health != RobotHealth::kOk || on_hold(hold, r)) {
      t.owed = 0;
      continue;
    }
    if (late(t) || t.revoked == ticks_ || t.stepped != steps_) t.owed = std::min(cfg_.catch_up, t.owed + 1);
    owing[r] = !late(t) && t.owed > 0 && static_cast<int>(t.path.size()) < cfg_.commit_horizon;
  }
  return owing;
}

std::string Executor::debug_queue(Cell c) const {
  std::string s;
  auto it = visits_.find(c);
  if (it == visits_.end()) return "no visits";
  for (int r : it->second) {
    const Track& t = tracks_[r];
    s += "robot " + std::to_string(r) + " at " + grid_.describe(t.cell) + " " + robot_health_name(t.health) +
         (t.dispatched ? " dispatched" : "") + " path";
    for (const Pose& p : t.path) s += " " + grid_.describe(p.cell) + (rotation() ? gdrhcr::heading_name(p.heading) : "");
    s += "; ";
  }
  return s;
}

std::vector<int> Executor::visitors(Cell c) const {
  auto it = visits_.find(c);
  return it == visits_.end() ? std::vector<int>{} : std::vector<int>(it->second.begin(), it->second.end());
}

std::string Executor::check_invariants() const {
  std::string err;
  for (int r = 0; r < num_robots() && err.empty(); ++r) {
    const Track& t = tracks_[r];
    if (!t.active) continue;
    const int a = agent_of_robot_[r];
    if (a < 0 || robot_of_agent_[a] != r) err = "robot " + std::to_string(r) + " is placed but not planner agent " + std::to_string(a);
    auto it = visits_.find(t.cell);
    if (it == visits_.end() || it->second.empty() || it->second.front() != r)
      err = "robot " + std::to_string(r) + " is not first in the queue of its cell " + grid_.describe(t.cell);
    Pose prev{t.cell, t.heading};
    for (const Pose& p : t.path) {
      const bool ok = rotation() ? gdrhcr::action_between(grid_, prev, p).has_value() && p != prev
                                 : grid_.step_allowed(prev.cell, p.cell) && p.cell != prev.cell;
      if (!ok)
        err = "robot " + std::to_string(r) + " has a committed move " + grid_.describe(prev.cell) + " -> " +
              grid_.describe(p.cell) + (rotation() ? std::string(" ") + gdrhcr::heading_name(prev.heading) + " -> " +
                                                         gdrhcr::heading_name(p.heading) : std::string());
      auto q = visits_.find(p.cell);
      if (q == visits_.end() || std::find(q->second.begin(), q->second.end(), r) == q->second.end())
        err = "robot " + std::to_string(r) + " has no visit queued for " + grid_.describe(p.cell);
      prev = p;
    }
  }
  return err;
}

}  // namespace gd_rhcr_planner
