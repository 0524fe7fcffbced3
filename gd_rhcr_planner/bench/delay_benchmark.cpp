// Delay-robust execution without ROS (issue 13): the planner node's execution layer (Executor,
// the Action Dependency Graph) and a core planner drive simulated robots (delayed_fleet.hpp: no safety
// interlock, LoRR-2026 random delays) with random goals; once without delays and once with
// p_delay per robot and tick, delays of 1..D ticks. Prints goals reached per tick, the ratio with
// delays to without, and robots delayed and waiting per tick; any collision, bad command or
// broken ADG invariant aborts the run. A benchmark (prints figures), not a test; seconds per run,
// so ideas can be tried here before the ROS benchmark (scripts/bench_delays.sh).
//   delay_benchmark --map maps/warehouse-10-20-10-2-1.map --robots 300 --ticks 300 --p-delay 0.01
//       --max-delay 20 --planner gd-rhcr --speed 6 --seeds 1 --commit-horizon 2
//       --between 1 [--param key=value ...]   (planner parameters, e.g. --param guidance=none; the
//       planner's table defaults, except that config/fleet.yaml gives the node lg-straight 1: add
//       --param lg-straight=1 for the node's planner)
// --help lists the options with their defaults and ranges; a bad value is an error naming it.
// --between 1 (default): moves are dispatched the moment the robots ahead have left (the node's
// dispatch timer, Executor::advance after every substep); 0: at ticks only. --revoke 1 (default):
// moves queued behind late robots are taken back and planned again (ExecutorConfig); 0: kept.
// --catch-up N (default 100, the node's): steps a robot that lost time (a tick it was late or got
// no move) may make up, one extra move per tick along its planned path (ExecutorConfig::catch_up);
// 0: off.
// --step-ticks M: a planning step stands for M ticks of the delay process (LoRR 2026's moves of 3
// ticks: --step-ticks 3 --speed 10); delays start with p_delay per tick and last 1..D ticks.
// --action-model rotation: the planner and the executor plan forward moves and quarter turns
// (LoRR's model; robots turn only when told, a quarter turn as long as a move); mapf (default):
// moves to any neighbour.
// --turning 1: the robots face a heading and turn (a quarter turn as long as a move) towards a
// neighbour they are sent to before moving, as fleet_sim's robots do while the node plans in the
// mapf model; 0 (default): they move to any neighbour at once.
// --late N: robots 0..N-1 are off the floor (they never reported) until --join-tick; then they
// report, at their cell if it is free, else at a free one (a robot joining the fleet late).
// Each robot's goals come from its own random stream, so both runs of a seed give every robot
// the same goal sequence. DELAY_BENCH_STATS=1 prints the planner's counters after each run;
// DELAY_BENCH_WHY=1 where the robots' time goes (moving, delayed, waiting behind a delayed robot or
// another, kept in place by the planner), robots per substep.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "bench_options.hpp"
#include "delayed_fleet.hpp"
#include "gd_rhcr_planner/execution.hpp"
#include "gd_rhcr_planner/map_loader.hpp"
#include "gdrhcr/params.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/planner_params.hpp"

using namespace gd_rhcr_planner;

namespace {

struct Options {
  std::string map = "maps/warehouse-10-20-10-2-1.map", planner = "gd-rhcr";
  int robots = 300, ticks = 300, max_delay = 20, speed = 6, seeds = 1, commit_horizon = 2, between = 1, revoke = 1, catch_up = 100;  // the node's defaults
  int late = 0, join_tick = 50;  // robots 0..late-1 are off the floor until join_tick
  int step_ticks = 1;            // ticks of the delay process per planning step (DelayedFleet::ticks_per_step)
  int turning = 0;               // robots turn before a move (DelayedFleet::give_headings)
  std::string action_model = "mapf";
  double p_delay = 0.01;
  std::vector<std::pair<std::string, std::string>> params;  // --param key=value, for the planner
};

// Where robot-time goes (DELAY_BENCH_WHY=1), robots per substep (sampled after substeps 1-9 of
// each tick, where dispatch on arrival runs): moving, delayed, dispatched and about to start,
// waiting on a committed move behind a delayed robot (directly or through robots waiting
// themselves), waiting behind a robot that is not delayed, and with no move committed (the
// planner keeps it in place; of those, how many are next to a delayed robot).
enum Why {
  kMoving, kDelayed, kStarting, kBehindLate, kBehindOther, kPlannedWait, kWaitNextToLate,
  kLateIn, kLateSent, kLateStarted, kLateQueued, kWhyCount
};
const char* const kWhyName[kWhyCount] = {
    "moving", "delayed", "starting", "behind-late", "behind-other", "planned-wait",
    "(of which next to a delayed robot)", "behind-late: it stands in the cell", "behind-late: sent into the cell, at rest",
    "behind-late: sent into the cell, stopped on the way",
    "behind-late: its later visit queued first"};

struct Result {
  double why[kWhyCount] = {};
  long why_samples = 0;
  int goals = 0;
  double delayed = 0, waiting = 0, held = 0, moves = 0;  // per tick
  long revoked = 0, caught_up = 0;
  std::string error;
};

// Why robot r waits for its committed move, when a delayed robot is the cause, directly or
// through robots that wait themselves: the delayed robot is in the cell the last robot of the
// chain waits for (kLateIn), was sent into it and has not started (kLateSent) or stopped on the
// way (kLateStarted), or is queued to visit it first (kLateQueued); kBehindOther otherwise.
Why behind_delayed(const Executor& ex, DelayedFleet& fleet, int r) {
  for (int depth = 0; depth < 64; ++depth) {
    const std::vector<Cell> path = ex.committed(r);
    if (path.empty() || ex.dispatched(r)) return kBehindOther;
    const std::vector<int> q = ex.visitors(path.front());
    if (q.empty() || q.front() == r) return kBehindOther;
    const int ahead = q.front();
    const SimRobot& s = fleet.robots()[ahead];
    if (s.delay > 0) {
      if (ex.cell(ahead) == path.front()) return kLateIn;
      if (!ex.dispatched(ahead) || ex.committed(ahead).front() != path.front()) return kLateQueued;
      return s.moving ? kLateStarted : kLateSent;
    }
    if (s.moving) return kBehindOther;
    r = ahead;
  }
  return kBehindOther;
}

// Adds where each robot's time goes now (after a substep) to res.why.
void account(const Executor& ex, DelayedFleet& fleet, const gdrhcr::Grid& g, Result& res) {
  const auto& rs = fleet.robots();
  std::vector<uint8_t> late(g.num_cells(), 0);
  for (const SimRobot& s : rs)
    if (s.delay > 0) late[s.cell] = 1;
  for (int r = 0; r < static_cast<int>(rs.size()); ++r) {
    const SimRobot& s = rs[r];
    Why w;
    if (s.delay > 0) w = kDelayed;
    else if (s.moving) w = kMoving;
    else if (ex.dispatched(r)) w = kStarting;
    else if (!ex.committed(r).empty()) {
      w = behind_delayed(ex, fleet, r);
      if (w != kBehindOther) {
        res.why[w] += 1;
        w = kBehindLate;
      }
    } else {
      w = kPlannedWait;
      for (Cell nb : g.neighbours(s.cell))
        if (late[nb]) {
          res.why[kWaitNextToLate] += 1;
          break;
        }
    }
    res.why[w] += 1;
  }
  ++res.why_samples;
}

Result run(const gdrhcr::Grid& g, const Options& o, double p_delay, uint64_t seed) {
  gdrhcr::Params params, none;
  // Node-budget mode: the same plans on any machine (no timeouts).
  if (o.planner == "gd-rhcr") params.set("timeout", "1e6"), params.set("node-budget", "2000");
  for (const auto& [k, v] : o.params) params.set(k, v);
  const gdrhcr::ActionModel model = gdrhcr::parse_action_model(o.action_model);
  const auto values = gdrhcr::PlannerParams::resolve(o.planner, params, gdrhcr::MapFacts(g, o.robots, model));
  params.check_all_used(o.planner);  // a misspelt --param is an error, not ignored
  const gdrhcr::DistTable dist(g, model, gdrhcr::DistTable::kDefaultBudgetBytes, gdrhcr::step_costs(values, model));
  auto primary = gdrhcr::make_planner(values, g, o.robots, seed, model);
  DeadlinePlanner planner(std::move(primary), gdrhcr::make_planner("pibt", none, g, o.robots, seed, model));
  ExecutorConfig cfg;
  cfg.action_model = model;
  cfg.commit_horizon = o.commit_horizon;
  cfg.revoke_behind_late = o.revoke != 0;
  cfg.catch_up = o.catch_up;
  Executor ex(g, dist, o.robots, cfg);
  DelayedFleet fleet(g, o.robots, seed, o.speed, o.speed);
  for (int i = 0; i < o.late; ++i) fleet.robots()[i].missing = true;
  fleet.ticks_per_step = o.step_ticks;
  if (model == gdrhcr::ActionModel::kRotation) fleet.give_headings(true);
  else if (o.turning) fleet.give_headings(false);
  Result r;
  const bool why = std::getenv("DELAY_BENCH_WHY") != nullptr;
  DelayedFleet::Between between;
  if (o.between) between = DelayedFleet::on_arrival(ex);
  if (why) {
    DelayedFleet::Between inner = between;
    between = [&, inner](const std::vector<RobotRecord>& reports) {
      std::vector<DelayedFleet::Command> cmds;
      if (inner) cmds = inner(reports);
      account(ex, fleet, g, r);
      return cmds;
    };
  }
  for (int t = 0; t < o.ticks; ++t) {
    if (t == o.join_tick)
      for (int i = 0; i < o.late; ++i) fleet.join(i);
    auto goals = fleet.goals(r.goals);
    const TickOutput out = ex.tick(fleet.records(), goals, planner, true);
    if (!out.stepped) r.error = "no step: " + out.skip_reason;
    else if (!out.plan_error.empty()) r.error = "plan rejected: " + out.plan_error;
    else r.error = ex.check_invariants();
    if (r.error.empty())
      r.error = fleet.execute(out, p_delay, o.max_delay, between);
    if (!r.error.empty()) {
      r.error = "tick " + std::to_string(t) + ": " + r.error;
      return r;
    }
    r.delayed += fleet.delayed();
    r.waiting += out.waiting;
    r.held += out.held;
    r.revoked += out.revoked;
    r.caught_up += out.caught_up;
  }
  for (const SimRobot& s : fleet.robots()) r.moves += s.moves;
  planner.wait_idle();
  if (std::getenv("DELAY_BENCH_STATS"))
    std::fprintf(stderr, "p %.3f: revoked %ld, catch-up moves %ld; %s\n", p_delay, r.revoked, r.caught_up, planner.primary().stats().dump().c_str());
  if (why) {
    std::fprintf(stderr, "p %g, robots per substep:", p_delay);
    for (int w = 0; w < kWhyCount; ++w) std::fprintf(stderr, " %s %.1f", kWhyName[w], r.why[w] / r.why_samples);
    std::fprintf(stderr, "\n");
  }
  r.delayed /= o.ticks;
  r.waiting /= o.ticks;
  r.held /= o.ticks;
  r.moves /= o.ticks;
  return r;
}

// The options from the command line; throws BenchOptionError naming a bad one.
Options read_options(const BenchOptions& cl) {
  Options o;
  o.map = cl.text("map", o.map);
  o.planner = cl.text("planner", o.planner);
  o.robots = static_cast<int>(cl.integer("robots", o.robots, 1, 1000000));
  o.ticks = static_cast<int>(cl.integer("ticks", o.ticks, 1, 10000000));
  o.p_delay = cl.real("p-delay", o.p_delay, 0, 1);
  o.max_delay = static_cast<int>(cl.integer("max-delay", o.max_delay, 1, 1000000));
  o.speed = static_cast<int>(cl.integer("speed", o.speed, 1, SimRobot::kSub));
  o.seeds = static_cast<int>(cl.integer("seeds", o.seeds, 1, 1000000));
  o.commit_horizon = static_cast<int>(cl.integer("commit-horizon", o.commit_horizon, 1, 1000));
  o.between = static_cast<int>(cl.integer("between", o.between, 0, 1));
  o.revoke = static_cast<int>(cl.integer("revoke", o.revoke, 0, 1));
  o.catch_up = static_cast<int>(cl.integer("catch-up", o.catch_up, 0, 1000));
  o.late = static_cast<int>(cl.integer("late", o.late, 0, o.robots));
  o.join_tick = static_cast<int>(cl.integer("join-tick", o.join_tick, 0, 10000000));
  o.step_ticks = static_cast<int>(cl.integer("step-ticks", o.step_ticks, 1, SimRobot::kSub));
  o.turning = static_cast<int>(cl.integer("turning", o.turning, 0, 1));
  o.action_model = cl.text("action-model", o.action_model);
  try {
    gdrhcr::parse_action_model(o.action_model);
  } catch (const std::exception& e) {
    throw BenchOptionError("--action-model: " + std::string(e.what()));
  }
  for (const std::string& kv : cl.all("param")) {
    const size_t eq = kv.find('=');
    if (eq == std::string::npos || eq == 0) throw BenchOptionError("--param must be key=value, not '" + kv + "'");
    o.params.emplace_back(kv.substr(0, eq), kv.substr(eq + 1));
  }
  return o;
}

void print_usage() {
  const Options d;
  std::printf(
      "delay_benchmark: the ADG execution layer and a planner drive simulated robots with random delays,\n"
      "once without and once with delays; prints goals per tick and their ratio.\n"
      "  --map PATH            map (%s)\n"
      "  --planner NAME        planner (%s)\n"
      "  --robots N            robots, 1.. the map's free cells (%d)\n"
      "  --ticks N             ticks per run (%d)\n"
      "  --p-delay P           probability per robot and tick that a delay starts, in [0, 1] (%g)\n"
      "  --max-delay D         delays last 1..D ticks (%d)\n"
      "  --speed S             substeps of a tick per move, 1..%d (%d)\n"
      "  --seeds N             seeds 1..N (%d)\n"
      "  --commit-horizon H    moves a robot may have committed and not finished, >= 1 (%d)\n"
      "  --between 0|1         dispatch on arrival between ticks (%d)\n"
      "  --revoke 0|1          take back moves queued behind late robots (%d)\n"
      "  --catch-up N          steps a robot that lost time (a tick late or without a move) may make up, 0..1000, 0 = off (%d)\n"
      "  --late N              robots 0..N-1 are off the floor (never reported) until --join-tick, 0..robots (%d)\n"
      "  --join-tick T         the tick at which they report (%d)\n"
      "  --step-ticks M        ticks of the delay process per planning step, 1..%d: a step stands for M ticks\n"
      "                        (moves of M ticks with --speed %d); p-delay and max-delay are per tick (%d)\n"
      "  --action-model M      mapf or rotation: the planner's and the executor's moves (%s)\n"
      "  --turning 0|1         robots turn towards a neighbour before moving, a quarter turn as long as a move (%d)\n"
      "  --param key=value     a planner parameter (repeatable)\n",
      d.map.c_str(), d.planner.c_str(), d.robots, d.ticks, d.p_delay, d.max_delay, SimRobot::kSub, d.speed, d.seeds,
      d.commit_horizon, d.between, d.revoke, d.catch_up, d.late, d.join_tick, SimRobot::kSub, SimRobot::kSub, d.step_ticks, d.action_model.c_str(), d.turning);
}

// Both runs of every seed and the figures; returns the exit code.
int run_all(const Options& o) {
  const LoadedMap map = load_map(o.map, 1.0);
  if (o.robots > static_cast<int>(map.grid.free_cells().size()))
    throw BenchOptionError("--robots " + std::to_string(o.robots) + ": the map has " +
                           std::to_string(map.grid.free_cells().size()) + " free cells");
  std::printf("map %s, %d robots, planner %s, ADG execution (commit horizon %d, dispatch %s, catch-up %d), %d ticks, "
              "moves take %.1f tick, delays p %g per tick of 1..%d ticks, random goals\n",
              o.map.c_str(), o.robots, o.planner.c_str(), o.commit_horizon, o.between ? "on arrival" : "at ticks",
              o.catch_up, o.ticks,
              o.speed / double(SimRobot::kSub), o.p_delay, o.max_delay);
  if (o.late > 0) std::printf("robots 0..%d join at tick %d\n", o.late - 1, o.join_tick);
  if (o.action_model != "mapf") std::printf("action model %s: robots turn only when told\n", o.action_model.c_str());
  if (o.turning) std::printf("robots turn towards a neighbour before moving (a quarter turn as long as a move)\n");
  if (o.step_ticks > 1) std::printf("a planning step stands for %d ticks of the delay process\n", o.step_ticks);
  std::printf("%5s %14s %14s %7s %16s %16s %12s %14s\n", "seed", "goals/tick no", "goals/tick p", "ratio",
              "delayed robots", "waiting no / p", "held moves", "moves no / p");
  double sum_ratio = 0;
  for (int s = 1; s <= o.seeds; ++s) {
    const Result a = run(map.grid, o, 0.0, s), b = run(map.grid, o, o.p_delay, s);
    for (const Result* r : {&a, &b})
      if (!r->error.empty()) {
        std::printf("seed %d: %s\n", s, r->error.c_str());
        return 1;
      }
    const double ta = double(a.goals) / o.ticks, tb = double(b.goals) / o.ticks;
    sum_ratio += tb / ta;
    std::printf("%5d %14.3f %14.3f %6.1f%% %16.1f %7.1f / %6.1f %5.1f / %4.1f %6.0f / %5.0f\n", s, ta, tb, 100 * tb / ta,
                b.delayed, a.waiting, b.waiting, a.held, b.held, a.moves, b.moves);
    std::fflush(stdout);
  }
  std::printf("mean ratio %.1f%%\n", 100 * sum_ratio / o.seeds);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    const BenchOptions cl(argc, argv, {"map", "planner", "robots", "ticks", "p-delay", "max-delay", "speed", "seeds",
                                       "commit-horizon", "between", "revoke", "catch-up", "late", "join-tick", "step-ticks", "action-model", "turning", "param"});
    if (cl.help()) {
      print_usage();
      return 0;
    }
    return run_all(read_options(cl));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "delay_benchmark: %s\n", e.what());
    return 2;
  }
}
