// Simulated delayed robots for execution tests and benchmarks; see delayed_fleet.hpp.
#include "delayed_fleet.hpp"

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace gd_rhcr_planner {

using gdrhcr::Cell;
using gdrhcr::kNoCell;
using gdrhcr::kNoHeading;

DelayedFleet::DelayedFleet(const gdrhcr::Grid& g, int n, uint64_t seed, int min_speed, int max_speed)
    : g_(g), rng_(seed), delay_rng_(seed * 0x9E3779B97F4A7C15ULL + 1), robots_(n) {
  // Each robot draws its goals from its own stream, so a run with delays gets the same goal
  // sequence per robot as one without (paired runs: the ratio is not drowned in task noise).
  for (int i = 0; i < n; ++i) {
    std::seed_seq seq{seed, uint64_t(i), uint64_t(0x60a15)};
    goal_rng_.emplace_back(seq);
  }
  std::vector<Cell> free = g.free_cells();
  std::shuffle(free.begin(), free.end(), rng_);
  std::uniform_int_distribution<int> speed(min_speed, max_speed);
  for (int i = 0; i < n; ++i) {
    robots_[i].cell = free[i];
    robots_[i].speed = speed(rng_);
    robots_[i].goal = random_cell(i);
  }
}

Cell DelayedFleet::random_cell(size_t robot) {
  const auto& f = g_.free_cells();
  return f[std::uniform_int_distribution<size_t>(0, f.size() - 1)(goal_rng_[robot])];
}

std::vector<RobotRecord> DelayedFleet::records() const {
  std::vector<RobotRecord> out(robots_.size());
  for (size_t i = 0; i < robots_.size(); ++i) {
    const SimRobot& s = robots_[i];
    if (s.missing) continue;
    out[i].reported = true;
    out[i].cell = s.fake != kNoCell ? s.fake : s.cell;
    out[i].moving = s.moving;
    out[i].reported_offline = s.offline;
    out[i].offline = s.offline || s.silent;
    out[i].silent = s.silent;
    out[i].heading = s.heading;
  }
  return out;
}

void DelayedFleet::give_headings(bool forward_only) {
  forward_only_ = forward_only;
  for (SimRobot& s : robots_) s.heading = static_cast<gdrhcr::Heading>(std::uniform_int_distribution<int>(0, 3)(rng_));
}

std::vector<std::vector<Cell>> DelayedFleet::goals(int& reached) {
  std::vector<std::vector<Cell>> out(robots_.size());
  std::unordered_map<Cell, int> dead;
  for (const SimRobot& s : robots_)
    if (!s.missing && (s.silent || s.offline)) dead[s.cell] = 1, dead[s.moving ? s.dst : s.cell] = 1;
  for (size_t i = 0; i < robots_.size(); ++i) {
    SimRobot& s = robots_[i];
    while (dead.count(s.goal)) s.goal = random_cell(i);
    if (!s.moving && s.cell == s.goal && !s.missing && !s.silent && !s.offline) {
      ++reached;
      ++s.goals_reached;
      s.goal = random_cell(i);
    }
    out[i] = {s.offline || s.silent ? s.cell : s.goal};
  }
  return out;
}

// Takes robot i's command c: a moving robot must be told the cell it is entering; a robot at rest
// remembers it and starts the move as soon as it is not delayed (see start_moves). A robot that
// reports a fake cell takes that cell for its own: told to stay there, it stays.
std::string DelayedFleet::take_command(size_t i, Cell c, gdrhcr::Heading h) {
  SimRobot& s = robots_[i];
  if (c == kNoCell || s.missing || s.silent) return "";
  s.cmd_heading = h;
  if (s.fake != kNoCell && c == s.fake) c = s.cell;
  if (s.moving) {
    if (c != s.dst)
      return "robot " + std::to_string(i) + " is moving to " + g_.describe(s.dst) + " but was commanded " + g_.describe(c);
    return "";
  }
  if (c != s.cell && !g_.step_allowed(s.cell, c))
    return "robot " + std::to_string(i) + ": " + g_.describe(s.cell) + " -> " + g_.describe(c);
  if (forward_only_ && c != s.cell && !s.turning && gdrhcr::heading_of_move(g_, s.cell, c) != s.heading)
    return "robot " + std::to_string(i) + " facing " + gdrhcr::heading_name(s.heading) + " in " + g_.describe(s.cell) +
           " was sent into " + g_.describe(c) + ", which it does not face";
  s.cmd = c;
  return "";
}

// A turning robot at rest that does not face its command's heading (a commanded neighbour's, else
// the commanded one) starts a quarter turn towards it. True while it must turn before it moves.
bool DelayedFleet::start_turn(SimRobot& s) {
  if (s.heading == kNoHeading || s.cmd == kNoCell) return false;
  const gdrhcr::Heading want = s.cmd != s.cell ? gdrhcr::heading_of_move(g_, s.cell, s.cmd) : s.cmd_heading;
  if (want == kNoHeading || want == s.heading) return false;
  if (!s.turning) {
    s.turning = gdrhcr::rotate_ccw(s.heading) == want ? -1 : 1;
    s.left = s.speed;
    ++s.turns;
    s.turns_before_moves += s.cmd != s.cell;
  }
  return true;
}

// Robots at rest, not delayed, with a command to a neighbour start it (a robot that will not move,
// offline or reporting a fake cell, does not); a turning robot turns to face it first.
void DelayedFleet::start_moves() {
  for (SimRobot& s : robots_) {
    if (s.offline && !s.moving) s.cmd = kNoCell;  // OFFLINE at rest cancels its move
    if (s.missing || s.silent || s.offline || s.fake != kNoCell || s.moving || s.delay > 0) continue;
    if (s.turning || start_turn(s)) continue;
    if (s.cmd == kNoCell || s.cmd == s.cell) continue;
    s.moving = true;
    s.dst = s.cmd;
    s.left = s.speed;
    ++s.moves;
  }
}

std::string DelayedFleet::execute(const TickOutput& out, double p_delay, int max_delay_ticks, const Between& between) {
  std::uniform_real_distribution<double> u(0, 1);
  std::uniform_int_distribution<int> d(1, std::max(1, max_delay_ticks));
  const int m = std::max(1, ticks_per_step);
  const double p_step = m == 1 ? p_delay : 1 - std::pow(1 - p_delay, m);
  for (size_t i = 0; i < robots_.size(); ++i) {
    SimRobot& s = robots_[i];
    if (s.missing || s.silent) continue;
    if (s.delay == 0 && p_delay > 0 && u(delay_rng_) < p_step)
      s.delay = m == 1 ? d(delay_rng_) * SimRobot::kSub : std::max(1, (d(delay_rng_) * SimRobot::kSub + m / 2) / m);
    std::string err = take_command(i, out.command[i], out.command_heading.empty() ? kNoHeading : out.command_heading[i]);
    if (!err.empty()) return err;
  }
  for (int k = 0; k < SimRobot::kSub; ++k) {
    start_moves();
    for (SimRobot& s : robots_) {
      if (s.silent) continue;
      if (s.delay > 0) {
        --s.delay;
        continue;
      }
      if (s.moving && --s.left <= 0) {
        s.cell = s.dst;
        s.moving = false;
      }
      if (s.turning && --s.left <= 0) {
        s.heading = static_cast<gdrhcr::Heading>((s.heading + s.turning) & 3);
        s.turning = 0;
      }
    }
    std::string err = check_physical();
    if (!err.empty()) return err;
    if (between && k + 1 < SimRobot::kSub)
      for (const Command& c : between(records())) {
        err = take_command(static_cast<size_t>(c.robot), c.cell, c.heading);
        if (!err.empty()) return err;
      }
  }
  return "";
}

DelayedFleet::Between DelayedFleet::on_arrival(Executor& ex) {
  return [&ex](const std::vector<RobotRecord>& reports) {
    std::vector<Command> cmds;
    for (int r : ex.advance(reports)) cmds.push_back({r, ex.command(r), ex.command_heading(r)});
    return cmds;
  };
}

// No cell holds two robots; a moving robot holds both its cells.
std::string DelayedFleet::check_physical() {
  std::unordered_map<Cell, int> at;
  for (size_t i = 0; i < robots_.size(); ++i) {
    const SimRobot& s = robots_[i];
    if (s.missing) continue;
    for (Cell c : {s.cell, s.moving ? s.dst : kNoCell}) {
      if (c == kNoCell) continue;
      auto [it, fresh] = at.emplace(c, static_cast<int>(i));
      if (!fresh) {
        collision_cell = c;
        return "robots " + std::to_string(it->second) + " and " + std::to_string(i) + " share cell " + g_.describe(c);
      }
    }
  }
  return "";
}

void DelayedFleet::join(size_t i) {
  SimRobot& s = robots_[i];
  s.missing = false;
  auto taken = [&](Cell c) {
    for (size_t j = 0; j < robots_.size(); ++j) {
      const SimRobot& o = robots_[j];
      if (j != i && !o.missing && (o.cell == c || o.cmd == c || (o.moving && o.dst == c))) return true;
    }
    return false;
  };
  if (!taken(s.cell)) return;
  for (Cell c : g_.free_cells())
    if (!taken(c)) {
      s.cell = c;
      return;
    }
}

int DelayedFleet::delayed() const {
  int n = 0;
  for (const SimRobot& s : robots_) n += s.delay > 0;
  return n;
}

}  // namespace gd_rhcr_planner
