// Executor (execution.hpp): the Action Dependency Graph, rotations, and the ADG under random delays: simulated robots that start a commanded move at once
// (no interlock), pause for random delays (LoRR 2026 style: p_delay per tick, 1..D ticks), move
// at different speeds, and occupy both cells while moving. Over many seeds: no two robots ever
// share a cell, every command is a wait or a move to a free neighbour, a command to a moving
// robot names its destination, and after the delays stop every robot reaches goals again (no
// deadlock). Bad robots (missing, silent, offline, inconsistent, slipping) leave the rest moving.
#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <memory>
#include <random>
#include <algorithm>

#include "delayed_fleet.hpp"
#include "gd_rhcr_planner/execution.hpp"
#include "gd_rhcr_planner/map_loader.hpp"
#include "gdrhcr/pibt.hpp"
#include "gdrhcr/planner.hpp"

using namespace gd_rhcr_planner;
using gdrhcr::Cell;
using gdrhcr::Grid;
using gdrhcr::kNoCell;

namespace {

// Plans whatever the test's function says (and, for catch-up, intends what `intends` says).
class FnPlanner : public gdrhcr::Planner {
 public:
  std::function<void(const gdrhcr::WorldView&, std::vector<Cell>&)> fn;
  std::function<Cell(int, Cell)> intends;
  std::string name() const override { return "fn"; }
  Cell intended_next(int agent, Cell at) const override { return intends ? intends(agent, at) : kNoCell; }
  gdrhcr::StepReport plan_step(const gdrhcr::WorldView& w, std::vector<Cell>& next) override {
    next = w.positions;
    if (fn) fn(w, next);
    return {true, 0};
  }
  nlohmann::json params() const override { return nlohmann::json::object(); }
};

// PIBT's step function as a planner, with its per-agent priorities in view.
class PibtStepPlanner : public gdrhcr::Planner {
 public:
  PibtStepPlanner(const Grid& g, int n) : step_(g, n, 1) {}
  std::string name() const override { return "pibt-step"; }
  gdrhcr::StepReport plan_step(const gdrhcr::WorldView& w, std::vector<Cell>& next) override {
    step_.step(w, next);
    return {true, 0};
  }
  nlohmann::json params() const override { return nlohmann::json::object(); }
  double priority(int agent) const { return step_.priority(agent); }

 private:
  gdrhcr::PibtStep step_;
};

std::unique_ptr<DeadlinePlanner> make_fn_planner(const Grid& g, int n, FnPlanner** out) {
  auto p = std::make_unique<FnPlanner>();
  *out = p.get();
  gdrhcr::Params none;
  return std::make_unique<DeadlinePlanner>(std::move(p), gdrhcr::make_planner("pibt", none, g, n, 1));
}

RobotRecord at(const Grid& g, int x, int y, bool moving = false) {
  RobotRecord r;
  r.reported = true;
  r.cell = g.cell(x, y);
  r.moving = moving;
  return r;
}

std::vector<std::vector<Cell>> stay_goals(const std::vector<RobotRecord>& robots) {
  std::vector<std::vector<Cell>> goals;
  for (auto& r : robots) goals.push_back({r.cell});
  return goals;
}

}  // namespace

// Robot 0 was commanded into (2,0) and is still moving at the next tick: it is late, so it gets no
// further move and robot 1 is not sent into the cell it enters; later robot 1 follows robot 0 out of (2,0), and is only sent in
// once robot 0 has reported arrival in its next cell, however long that takes.
TEST(ExecutorAdg, ACellIsEnteredOnlyAfterTheRobotsBeforeHaveLeftIt) {
  const Grid g = Grid::from_rows({"......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 2, &fn);
  ExecutorConfig cfg;
  cfg.revoke_behind_late = false;  // robot 1's follow move stays committed while robot 0 is late
  Executor ex(g, dist, 2, cfg);
  std::vector<RobotRecord> robots{at(g, 1, 0), at(g, 3, 0)};
  int step = 0;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    if (step == 0) next[0] = g.cell(2, 0);
    if (step == 1) {
      EXPECT_EQ(w.positions[0], g.cell(2, 0));  // planned from the committed end state
      EXPECT_TRUE(w.is_immovable(0));           // late: no further move for now
      next[1] = g.cell(2, 0);                   // a bad plan: the step is held instead
    }
    if (step == 2) {
      next[0] = g.cell(1, 0);
      next[1] = g.cell(2, 0);  // follows robot 0 out of (2,0)
    }
    ++step;
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(2, 0));
  robots[0].moving = true;  // a slow move: still on its way at the next tick
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(2, 0)) << "a moving robot is told its destination";
  EXPECT_EQ(out.command[1], g.cell(3, 0)) << "robot 1 was sent into the cell robot 0 is entering";
  EXPECT_EQ(ex.check_invariants(), "");
  robots[0] = at(g, 2, 0);  // arrived: its move back is dispatched, robot 1's follow move waits
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(1, 0));
  EXPECT_EQ(out.command[1], g.cell(3, 0));
  EXPECT_EQ(out.waiting, 1);
  EXPECT_EQ(ex.visitors(g.cell(2, 0)), (std::vector<int>{0, 1})) << "robot 0 is in (2,0), robot 1 queued after it";
  robots[0].moving = true;  // slow again
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[1], g.cell(3, 0));
  robots[0] = at(g, 1, 0);  // left (2,0): now robot 1 goes
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[1], g.cell(2, 0));
  EXPECT_EQ(ex.check_invariants(), "");
}

TEST(HoldRotations, ACycleOfFollowersWaitsAndAChainDoesNot) {
  const Grid g = Grid::from_rows({"...", "..."});
  // Four robots rotating around the 2x2 block on the left: each enters the cell the next leaves.
  std::vector<Cell> pos{g.cell(0, 0), g.cell(1, 0), g.cell(1, 1), g.cell(0, 1)};
  std::vector<Cell> next{g.cell(1, 0), g.cell(1, 1), g.cell(0, 1), g.cell(0, 0)};
  std::vector<uint8_t> held(4, 0);
  EXPECT_EQ(hold_rotations(pos, next, held), 4);
  EXPECT_EQ(next, pos);
  // A chain whose head enters a free cell is not a cycle.
  std::vector<Cell> cpos{g.cell(0, 0), g.cell(1, 0), g.cell(2, 0)};
  std::vector<Cell> cnext{g.cell(1, 0), g.cell(2, 0), g.cell(2, 1)};
  std::vector<uint8_t> cheld(3, 0);
  EXPECT_EQ(hold_rotations(cpos, cnext, cheld), 0);
  EXPECT_EQ(cheld, std::vector<uint8_t>(3, 0));
  // A swap is a 2-cycle.
  std::vector<Cell> p2{g.cell(0, 0), g.cell(1, 0)}, n2{g.cell(1, 0), g.cell(0, 0)};
  std::vector<uint8_t> h2(2, 0);
  EXPECT_EQ(hold_rotations(p2, n2, h2), 2);
}

TEST(Executor, BadHorizonIsRejected) {
  const Grid g = Grid::from_rows({"..."});
  gdrhcr::DistTable dist(g);
  ExecutorConfig cfg;
  cfg.commit_horizon = 0;
  EXPECT_THROW(Executor(g, dist, 1, cfg), gdrhcr::ParamError);
}

// ---------------------------------------------------------------------------------------------
// A simulated fleet for the randomised tests.

namespace {

struct SimResult {
  int goals = 0, goals_tail = 0, ticks = 0;
  int caught_up = 0;                      // catch-up moves (ExecutorConfig::catch_up)
  std::vector<RobotHealth> final_health;  // per robot, at the last tick
  std::vector<int> moves_tail;  // moves per robot after the delays stopped
  int max_wait_tail = 0;        // longest stretch a healthy robot waited on a committed move, tail
  std::vector<std::vector<int>> health_ticks;  // per robot, ticks spent in each RobotHealth
};

// Seeds per randomised test: the default, or EXEC_TEST_SEEDS (a longer soak by hand).
uint64_t seeds(uint64_t def) {
  const char* e = std::getenv("EXEC_TEST_SEEDS");
  return e ? std::strtoull(e, nullptr, 10) : def;
}

const Grid& small_warehouse() {
  static const LoadedMap m = load_map(std::string(GD_RHCR_MAPS_DIR) + "/warehouse_small.yaml", 1.0);
  return m.grid;
}

// Runs `ticks` ticks with delays, then `tail` ticks without.
SimResult run_fleet(const std::string& planner_name, int n, uint64_t seed, int ticks, int tail, double p_delay,
                    int max_delay, const std::function<void(int, DelayedFleet&)>& faults = nullptr,
                    int commit_horizon = 1, bool between = false, const std::vector<int>& restarts = {},
                    int catch_up = 0, int max_speed = 14) {
  const Grid& g = small_warehouse();
  gdrhcr::DistTable dist(g);
  gdrhcr::Params params, none;
  if (planner_name == "gd-rhcr") params.set("timeout", "1"), params.set("node-budget", "2000");
  ExecutorConfig cfg;
  cfg.commit_horizon = commit_horizon;
  cfg.catch_up = catch_up;
  std::unique_ptr<DeadlinePlanner> planner_ptr;
  std::unique_ptr<Executor> ex_ptr;
  // A fresh planner and executor (a restarted planner process) know nothing of the moves made.
  auto start = [&] {
    planner_ptr = std::make_unique<DeadlinePlanner>(gdrhcr::make_planner(planner_name, params, g, n, seed),
                                                    gdrhcr::make_planner("pibt", none, g, n, seed));
    ex_ptr = std::make_unique<Executor>(g, dist, n, cfg);
  };
  start();
  DelayedFleet sim(g, n, seed, 3, max_speed);
  // Dispatch on arrival: the executor sees the robots' reports after every substep, and the ADG
  // invariants hold after each of those dispatches too.
  DelayedFleet::Between on_arrival = [&](const std::vector<RobotRecord>& reports) {
    auto cmds = DelayedFleet::on_arrival(*ex_ptr)(reports);
    EXPECT_EQ(ex_ptr->check_invariants(), "");
    return cmds;
  };
  SimResult res;
  res.moves_tail.assign(n, 0);
  res.health_ticks.assign(n, std::vector<int>(5, 0));
  std::vector<int> wait_run(n, 0);
  for (int t = 0; t < ticks + tail; ++t) {
    if (faults) faults(t, sim);
    if (std::find(restarts.begin(), restarts.end(), t) != restarts.end()) start();
    Executor& ex = *ex_ptr;
    DeadlinePlanner& planner = *planner_ptr;
    if (t == ticks) std::fill(wait_run.begin(), wait_run.end(), 0);  // the tail counts waits that start in it
    int reached = 0;
    auto goals = sim.goals(reached);
    res.goals += reached;
    if (t >= ticks) res.goals_tail += reached;
    auto out = ex.tick(sim.records(), goals, planner, true);
    EXPECT_TRUE(out.stepped) << out.skip_reason;
    res.caught_up += out.caught_up;
    if (std::getenv("EXEC_DEBUG"))
      for (auto& w : out.warnings) fprintf(stderr, "seed %lu t=%d %s\n", (unsigned long)seed, t, w.c_str());
    EXPECT_EQ(out.plan_error, "") << "seed " << seed << " tick " << t;
    const std::string inv = ex.check_invariants();
    EXPECT_EQ(inv, "") << "seed " << seed << " tick " << t;
    if (!inv.empty()) return res;
    std::vector<int> before(n);
    for (int i = 0; i < n; ++i) before[i] = sim.robots()[i].moves;
    const std::string bad = sim.execute(out, t < ticks ? p_delay : 0.0, max_delay, between ? on_arrival : nullptr);
    if (!bad.empty()) {
      ADD_FAILURE() << bad;
      ADD_FAILURE() << "planner " << planner_name << " seed " << seed << " tick " << t << " queue at the collision: "
                    << (sim.collision_cell != kNoCell ? ex.debug_queue(sim.collision_cell) : std::string("-"));
      return res;
    }
    for (int i = 0; i < n; ++i) {
      ++res.health_ticks[i][static_cast<int>(out.health[i])];
      const int moved = sim.robots()[i].moves - before[i];
      if (t >= ticks) res.moves_tail[i] += moved;
      const bool waits = out.health[i] == RobotHealth::kOk && !ex.committed(i).empty() && !ex.dispatched(i);
      wait_run[i] = waits ? wait_run[i] + 1 : 0;
      if (getenv("EXEC_DEBUG") && wait_run[i] == 25) {
        const Cell c = ex.committed(i)[0];
        fprintf(stderr, "t=%d robot %d at %s waits to enter %s (%s)\n", t, i, small_warehouse().describe(ex.cell(i)).c_str(),
                small_warehouse().describe(c).c_str(), ex.debug_queue(c).c_str());
      }
      if (t >= ticks) res.max_wait_tail = std::max(res.max_wait_tail, wait_run[i]);
    }
    ++res.ticks;
    res.final_health = out.health;
    if (std::getenv("EXEC_DEBUG") && t + 1 == ticks + tail)
      for (int i = 0; i < n; ++i)
        fprintf(stderr, "seed %lu end robot %d at %s %s goal %s moves_tail %d committed %zu\n", (unsigned long)seed, i,
                g.describe(ex.cell(i)).c_str(), robot_health_name(out.health[i]), g.describe(sim.robots()[i].goal).c_str(),
                res.moves_tail[i], ex.committed(i).size());
  }
  return res;
}

}  // namespace

// The property of issue 13: any delay pattern, no collision, and no deadlock. 40 seeds with PIBT,
// 30 robots on the 32x17 warehouse crop, p_delay 0.05 per tick (5x the benchmark's), delays of
// 1..20 ticks, speeds 0.3..1.4 ticks per move; then 60 ticks without delays, in which every robot
// moves and the fleet reaches goals, and no robot waits long on a committed move.
TEST(ExecutorAdg, RandomDelaysNeverCollideNorDeadlock_Pibt) {
  for (uint64_t seed = 1; seed <= seeds(40); ++seed) {
    const SimResult r = run_fleet("pibt", 30, seed, 150, 60, 0.05, 20);
    if (HasFailure()) return;
    EXPECT_GT(r.goals_tail, 0) << "seed " << seed;
    EXPECT_LE(r.max_wait_tail, 30) << "seed " << seed << ": a robot waited " << r.max_wait_tail
                                   << " ticks on a committed move without delays";
  }
}

// The same with GD-RHCR (its cached group plans must follow the committed end states).
TEST(ExecutorAdg, RandomDelaysNeverCollideNorDeadlock_GdRhcr) {
  for (uint64_t seed = 1; seed <= seeds(8); ++seed) {
    const SimResult r = run_fleet("gd-rhcr", 30, seed, 120, 60, 0.05, 20);
    if (HasFailure()) return;
    EXPECT_GT(r.goals_tail, 0) << "seed " << seed;
    EXPECT_LE(r.max_wait_tail, 30) << "seed " << seed;
  }
}

// The same with moves dispatched the moment the robots ahead have left (Executor::advance between
// ticks) and two moves committed ahead, the node's default.
TEST(ExecutorAdg, RandomDelaysNeverCollideNorDeadlock_DispatchOnArrival) {
  for (uint64_t seed = 1; seed <= seeds(20); ++seed) {
    for (const char* planner : {"pibt", "gd-rhcr"}) {
      if (std::string(planner) == "gd-rhcr" && seed > 6) continue;
      const SimResult r = run_fleet(planner, 30, seed, 150, 60, 0.05, 20, nullptr, 2, true);
      if (HasFailure()) return;
      EXPECT_GT(r.goals_tail, 0) << planner << " seed " << seed;
      EXPECT_LE(r.max_wait_tail, 30) << planner << " seed " << seed;
    }
  }
}

// The same with catch-up (the node's default): robots that lost time make extra moves along their
// planned paths. Still no collision and no deadlock. Without delays, in a fleet whose moves all
// take less than a tick, the only steps owed are the plan's own waits, and making them up costs
// no goals.
TEST(ExecutorAdg, RandomDelaysNeverCollideNorDeadlock_CatchUp) {
  for (uint64_t seed = 1; seed <= seeds(12); ++seed) {
    for (const char* planner : {"pibt", "gd-rhcr"}) {
      if (std::string(planner) == "gd-rhcr" && seed > 6) continue;
      const SimResult r = run_fleet(planner, 30, seed, 150, 60, 0.05, 20, nullptr, 2, true, {}, 100);
      if (HasFailure()) return;
      EXPECT_GT(r.goals_tail, 0) << planner << " seed " << seed;
      EXPECT_LE(r.max_wait_tail, 30) << planner << " seed " << seed;
      if (std::string(planner) == "gd-rhcr") EXPECT_GT(r.caught_up, 0) << "seed " << seed;
    }
  }
  const SimResult calm = run_fleet("gd-rhcr", 30, 1, 100, 0, 0.0, 20, nullptr, 2, true, {}, 100, 9);
  const SimResult calm_off = run_fleet("gd-rhcr", 30, 1, 100, 0, 0.0, 20, nullptr, 2, true, {}, 0, 9);
  EXPECT_GT(calm_off.goals, 0);
  EXPECT_GE(calm.goals, calm_off.goals) << "no delay: making up the plan's waits costs no goals";
}

// Catch-up tests: an executor with two moves committed and catch_up steps owed at most, over a
// scripted planner (FnPlanner) on a small grid.
struct CatchUpRig {
  CatchUpRig(const std::vector<std::string>& rows, int n, int catch_up)
      : g(Grid::from_rows(rows)), dist(g), planner(make_fn_planner(g, n, &fn)), ex(g, dist, n, config(catch_up)) {}
  static ExecutorConfig config(int catch_up) {
    ExecutorConfig cfg;
    cfg.commit_horizon = 2;
    cfg.catch_up = catch_up;
    return cfg;
  }
  const Grid g;
  gdrhcr::DistTable dist;
  FnPlanner* fn = nullptr;
  std::unique_ptr<DeadlinePlanner> planner;
  Executor ex;
};

// Catch-up, step by step: robot 0 is late for two ticks (its queued move is taken back), then
// arrives with nothing committed. In that tick it gets its planned move and, owed steps, one more
// along the planner's intended path, so it is two cells on at once; without catch-up only one.
// Robot 1, which never lost time, gets no extra move, and nobody is sent towards a cell another
// robot's commitments end in.
TEST(ExecutorAdg, ARobotThatLostTimeMakesItUpAlongItsPlannedPath) {
  for (int catch_up : {0, 100}) {
    CatchUpRig rig({"........", "........"}, 2, catch_up);
    const Grid& g = rig.g;
    FnPlanner* fn = rig.fn;
    auto& planner = rig.planner;
    Executor& ex = rig.ex;
    std::vector<RobotRecord> robots{at(g, 0, 0), at(g, 0, 1)};
    int step = 0;
    fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
      ++step;
      for (int a = 0; a < 2; ++a) {
        if (w.is_immovable(a)) continue;
        if (a == 0 && step == 3) continue;  // robot 0 is planned to wait while it is late
        const int x = g.x_of(w.positions[a]);
        if (x + 1 < g.width()) next[a] = g.cell(x + 1, g.y_of(w.positions[a]));
      }
    };
    fn->intends = [&](int, Cell c) { return g.x_of(c) + 1 < g.width() ? c + 1 : kNoCell; };
    auto out = ex.tick(robots, stay_goals(robots), *planner, false);  // tick 1: both sent east
    EXPECT_EQ(out.command[0], g.cell(1, 0));
    EXPECT_EQ(out.caught_up, 0) << "nobody has lost time";
    robots[0].moving = true;  // tick 2: robot 0 is late; robot 1 arrived
    robots[1] = at(g, 1, 1);
    out = ex.tick(robots, stay_goals(robots), *planner, false);
    EXPECT_EQ(out.caught_up, 0) << "a late robot makes no extra move";
    robots[1] = at(g, 2, 1);
    out = ex.tick(robots, stay_goals(robots), *planner, false);  // tick 3: still late
    EXPECT_EQ(out.revoked, 1);
    EXPECT_EQ(out.caught_up, 0);
    robots[0] = at(g, 1, 0);  // tick 4: arrived, nothing committed any more
    robots[1] = at(g, 3, 1);
    out = ex.tick(robots, stay_goals(robots), *planner, false);
    EXPECT_EQ(ex.check_invariants(), "");
    EXPECT_EQ(out.command[0], g.cell(2, 0));
    if (catch_up > 0) {
      EXPECT_EQ(out.caught_up, 1);
      EXPECT_EQ(ex.committed(0), (std::vector<Cell>{g.cell(2, 0), g.cell(3, 0)})) << "two cells on in one tick";
    } else {
      EXPECT_EQ(out.caught_up, 0);
      EXPECT_EQ(ex.committed(0), std::vector<Cell>{g.cell(2, 0)});
    }
    EXPECT_EQ(ex.committed(1).size(), 1u) << "robot 1 never lost time";
  }
}

// A step the plan made a robot wait is owed too: robot 0 is planned to wait at step 2 (say,
// for a robot that has since gone). No robot's commitments end in the cell ahead, so it makes
// the step up in the same tick; at step 3 it owes nothing and gets its planned move only.
TEST(ExecutorAdg, AWaitInThePlanIsMadeUpWhenTheWayIsClear) {
  CatchUpRig rig({"........"}, 1, 100);
  const Grid& g = rig.g;
  FnPlanner* fn = rig.fn;
  auto& planner = rig.planner;
  Executor& ex = rig.ex;
  std::vector<RobotRecord> robots{at(g, 0, 0)};
  int step = 0;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    if (++step != 2) next[0] = w.positions[0] + 1;
  };
  fn->intends = [&](int, Cell c) { return g.x_of(c) + 1 < g.width() ? c + 1 : kNoCell; };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);  // step 1: east
  EXPECT_EQ(out.caught_up, 0);
  robots[0] = at(g, 1, 0);
  out = ex.tick(robots, stay_goals(robots), *planner, false);  // step 2: planned to wait
  EXPECT_EQ(out.caught_up, 1) << "the wait is owed and made up at once";
  EXPECT_EQ(out.command[0], g.cell(2, 0));
  EXPECT_EQ(ex.committed(0), std::vector<Cell>{g.cell(2, 0)});
  robots[0] = at(g, 2, 0);
  out = ex.tick(robots, stay_goals(robots), *planner, false);  // step 3: east, nothing owed
  EXPECT_EQ(out.caught_up, 0);
  EXPECT_EQ(ex.committed(0), std::vector<Cell>{g.cell(3, 0)});
  EXPECT_EQ(ex.check_invariants(), "");
}

// Catch-up never sends a robot into a cell another robot's commitments end in: robot 0 is owed
// steps, but the cell its planner intends next is where robot 1 ends; it makes no extra move.
TEST(ExecutorAdg, CatchUpKeepsOutOfCellsOthersEndIn) {
  CatchUpRig rig({"......"}, 2, 100);
  const Grid& g = rig.g;
  FnPlanner* fn = rig.fn;
  auto& planner = rig.planner;
  Executor& ex = rig.ex;
  std::vector<RobotRecord> robots{at(g, 0, 0), at(g, 3, 0)};
  int step = 0;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    if (++step == 1 || step == 4) next[0] = w.positions[0] + 1;  // robot 0 east; robot 1 stays
  };
  fn->intends = [&](int agent, Cell c) { return agent == 0 ? c + 1 : kNoCell; };
  ex.tick(robots, stay_goals(robots), *planner, false);
  robots[0].moving = true;
  ex.tick(robots, stay_goals(robots), *planner, false);
  ex.tick(robots, stay_goals(robots), *planner, false);
  robots[0] = at(g, 1, 0);
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);  // robot 0 to (2,0); (3,0) is robot 1's
  EXPECT_EQ(out.command[0], g.cell(2, 0));
  EXPECT_EQ(out.caught_up, 0);
  EXPECT_EQ(ex.committed(0), std::vector<Cell>{g.cell(2, 0)});
  EXPECT_EQ(ex.check_invariants(), "");
}

// Bad robots: robot 0 never reports (not on the floor), robot 1 falls silent mid-move for good,
// robot 2 goes offline at tick 40 and comes back at 90, robot 3 reports another robot's cell,
// three or more cells away, for ten ticks (then its own again), robot 5 slips into a free neighbour. The rest keeps moving and
// reaching goals, with delays, and nobody ever shares a cell with a robot (the silent one counts
// as being in both cells of its move).
TEST(ExecutorAdg, BadRobotsBecomeObstaclesAndTheRestKeepsMoving) {
  for (uint64_t seed = 1; seed <= seeds(10); ++seed) {
    const Grid& g = small_warehouse();
    int fake_from = -1;
    auto faults = [&](int t, DelayedFleet& sim) {
      auto& r = sim.robots();
      if (t == 0) r[0].missing = true;
      if (t == 30 && !r[1].silent) r[1].silent = true;
      if (t == 40) r[2].offline = true;
      if (t == 90) r[2].offline = false;
      // From the first tick >= 50 at which it is at rest, for ten ticks, robot 3 reports the cell of
      // a robot three or more cells away (a report no move of it can explain).
      if (t >= 50 && fake_from < 0 && !r[3].moving)
        for (int j = 4; j < 24 && r[3].fake == kNoCell; ++j)
          if (!r[j].moving && std::abs(g.x_of(r[3].cell) - g.x_of(r[j].cell)) + std::abs(g.y_of(r[3].cell) - g.y_of(r[j].cell)) >= 3)
            r[3].fake = r[j].cell, fake_from = t;
      if (fake_from >= 0 && t == fake_from + 10) r[3].fake = kNoCell;
      if (t == 70 && !r[5].moving && r[5].delay == 0) {  // slips: ends in a free neighbour nobody holds
        for (Cell nb : g.neighbours(r[5].cell)) {
          bool held = false;
          for (auto& o : r)
            held |= !o.missing && (o.cell == nb || (o.moving && o.dst == nb));
          if (!held) {
            r[5].cell = nb;
            break;
          }
        }
      }
    };
    const SimResult res = run_fleet("pibt", 24, seed, 150, 60, 0.02, 20, faults);
    if (HasFailure()) return;
    EXPECT_GT(res.goals_tail, 0) << "seed " << seed;
    int movers = 0;
    for (int i = 2; i < 24; ++i) movers += res.moves_tail[i] > 0;
    // The fleet is not frozen: a good share of the healthy robots keep moving (some may stay boxed
    // in behind the dead robot, or in a crowded dead end where PIBT keeps them waiting: a planner
    // matter, with no commitment involved), and no robot waits long on a committed move.
    EXPECT_GE(movers, 8) << "seed " << seed << ": the healthy robots should keep moving";
    EXPECT_LE(res.max_wait_tail, 30) << "seed " << seed;
    EXPECT_EQ(res.moves_tail[1], 0);
    // Each fault was seen as such (the test is not vacuous).
    EXPECT_EQ(res.health_ticks[0][int(RobotHealth::kMissing)], res.ticks);
    EXPECT_GT(res.health_ticks[1][int(RobotHealth::kSilent)], 100);
    EXPECT_GE(res.health_ticks[2][int(RobotHealth::kOffline)], 40);
    EXPECT_GT(res.health_ticks[3][int(RobotHealth::kInconsistent)], 0) << "seed " << seed;
  }
}

// Between ticks a robot behind another is sent into its cell once that robot reports arrival in
// the next cell (not while it is still moving), and a robot on hold is not. Hold flags count for
// the call they are given to only: each call gets its own, short-lived vector (the executor
// used to keep a pointer to the caller's flags).
TEST(ExecutorAdg, ARobotBehindGoesAsSoonAsTheOneAheadHasArrived) {
  const Grid g = Grid::from_rows({"......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 2, &fn);
  for (bool on_hold : {false, true}) {
    Executor ex(g, dist, 2, ExecutorConfig{});
    std::vector<RobotRecord> robots{at(g, 2, 0), at(g, 1, 0)};
    fn->fn = [&](const gdrhcr::WorldView&, std::vector<Cell>& next) {
      next[0] = g.cell(3, 0);
      next[1] = g.cell(2, 0);  // follows robot 0
    };
    auto out = ex.tick(robots, stay_goals(robots), *planner, false);
    EXPECT_EQ(out.command[0], g.cell(3, 0));
    EXPECT_EQ(out.command[1], g.cell(1, 0)) << "robot 0 is still in (2,0)";
    EXPECT_EQ(out.waiting, 1);
    auto hold = [&] { return std::make_unique<std::vector<uint8_t>>(std::vector<uint8_t>{0, on_hold}); };
    robots[0].moving = true;
    EXPECT_TRUE(ex.advance(robots, hold().get()).empty()) << "robot 0 has not left (2,0) yet";
    EXPECT_EQ(ex.command(1), g.cell(1, 0));
    robots[0] = at(g, 3, 0);  // arrived
    const std::vector<int> sent = ex.advance(robots, hold().get());
    EXPECT_EQ(ex.cell(0), g.cell(3, 0));
    EXPECT_EQ(ex.check_invariants(), "");
    if (on_hold) {
      EXPECT_TRUE(sent.empty());
      EXPECT_EQ(ex.command(1), g.cell(1, 0));
      // The next tick, without flags: robot 1 is released and sent.
      fn->fn = nullptr;
      out = ex.tick(robots, stay_goals(robots), *planner, false);
      EXPECT_EQ(out.command[1], g.cell(2, 0));
      EXPECT_EQ(out.waiting, 0);
    } else {
      EXPECT_EQ(sent, std::vector<int>{1});
      EXPECT_EQ(ex.command(1), g.cell(2, 0));
      EXPECT_TRUE(ex.advance(robots, hold().get()).empty()) << "nothing new: nothing sent twice";
    }
  }
}

// Robot 0 is late (still on its way at the next tick); robot 1 waits to enter the cell robot 0 has
// not left, and robot 2 to enter robot 1's. Both moves were only committed, not sent: they are
// taken back and the planner plans both robots again from their cells, with robot 0's cell blocked.
TEST(ExecutorAdg, MovesQueuedBehindALateRobotAreTakenBackTransitively) {
  const Grid g = Grid::from_rows({"......", "......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 3, &fn);
  Executor ex(g, dist, 3, ExecutorConfig{});
  std::vector<RobotRecord> robots{at(g, 2, 0), at(g, 1, 0), at(g, 0, 0)};
  int step = 0;
  std::vector<Cell> seen_pos, seen_blocked;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    if (step++ == 0) {  // a train: each robot follows the one ahead
      next = {g.cell(3, 0), g.cell(2, 0), g.cell(1, 0)};
      return;
    }
    seen_pos = w.positions;
    seen_blocked = w.blocked ? *w.blocked : std::vector<Cell>{};
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(3, 0));
  EXPECT_EQ(out.waiting, 2);
  robots[0].moving = true;  // late
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.revoked, 2);
  EXPECT_EQ(ex.check_invariants(), "");
  EXPECT_EQ(seen_pos, (std::vector<Cell>{g.cell(3, 0), g.cell(1, 0), g.cell(0, 0)}));
  EXPECT_EQ(seen_blocked, std::vector<Cell>{g.cell(2, 0)}) << "the late robot's cell is blocked";
  EXPECT_EQ(out.command[0], g.cell(3, 0)) << "a dispatched move is never taken back";
  EXPECT_TRUE(ex.committed(1).empty());
  EXPECT_TRUE(ex.committed(2).empty());
}

// Issue 22: a robot keeps its planner agent index, and with it the planner's state for it (here
// its PIBT priority), when another robot joins late. Robot 0 is not on the floor for three ticks;
// robots 1 and 2 are agents 0 and 1 and head for far goals, their priorities growing each step.
// Then robot 0 reports: it becomes agent 2, and robot 2 is still agent 1 with its priority one
// step higher. (Before, the planner's agents were the placed robots in id order: robot 2 became
// agent 2 with a fresh priority, and robot 1 inherited robot 2's state.)
TEST(ExecutorAdg, ARobotKeepsItsAgentIndexWhenAnotherJoinsLate) {
  const Grid g = Grid::from_rows({"........", "........", "........"});
  gdrhcr::DistTable dist(g);
  auto pibt = std::make_unique<PibtStepPlanner>(g, 3);
  const PibtStepPlanner& agents = *pibt;
  gdrhcr::Params none;
  DeadlinePlanner planner(std::move(pibt), gdrhcr::make_planner("pibt", none, g, 3, 1));
  Executor ex(g, dist, 3, ExecutorConfig{});
  std::vector<RobotRecord> robots{RobotRecord{}, at(g, 0, 0), at(g, 0, 2)};  // robot 0: no report yet
  const std::vector<std::vector<Cell>> goals{{g.cell(4, 1)}, {g.cell(7, 0)}, {g.cell(7, 2)}};
  double priority_of_robot2 = 0;
  for (int tick = 0; tick < 4; ++tick) {
    if (tick == 3) robots[0] = at(g, 4, 1);  // robot 0 reports, late
    const TickOutput out = ex.tick(robots, goals, planner, true);
    ASSERT_TRUE(out.stepped) << out.skip_reason;
    EXPECT_EQ(ex.check_invariants(), "");
    EXPECT_EQ(out.robot_of_agent, tick < 3 ? std::vector<int>({1, 2}) : std::vector<int>({1, 2, 0}));
    EXPECT_EQ(ex.agent_of(2), 1);
    EXPECT_EQ(ex.agent_of(0), tick < 3 ? -1 : 2);
    EXPECT_NE(out.command[2], robots[2].cell) << "robot 2 heads for its goal at tick " << tick;
    if (tick > 0) EXPECT_DOUBLE_EQ(agents.priority(1), priority_of_robot2 + 1) << "robot 2's priority at tick " << tick;
    priority_of_robot2 = agents.priority(1);
    for (int r : {1, 2}) robots[r].cell = out.command[r];  // arrived
  }
}

// A robot on hold (paused, emergency stop) gets no new move and is an obstacle to the planner;
// released, it goes on.
TEST(ExecutorAdg, ARobotOnHoldGetsNoNewMove) {
  const Grid g = Grid::from_rows({"......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 1, &fn);
  Executor ex(g, dist, 1, ExecutorConfig{});
  std::vector<RobotRecord> robots{at(g, 1, 0)};
  std::vector<uint8_t> seen;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    seen = w.immovable ? *w.immovable : std::vector<uint8_t>{0};
    if (!seen[0]) next[0] = g.cell(2, 0);
  };
  std::vector<uint8_t> hold{1};
  auto out = ex.tick(robots, {{g.cell(5, 0)}}, *planner, false, &hold);
  EXPECT_EQ(out.command[0], g.cell(1, 0));
  EXPECT_EQ(seen, std::vector<uint8_t>{1});
  hold[0] = 0;
  out = ex.tick(robots, {{g.cell(5, 0)}}, *planner, false, &hold);
  EXPECT_EQ(out.command[0], g.cell(2, 0));
}

// Issue 25: robot 0 is commanded into (2,0) but is delayed and still at rest in (1,0); robot 1
// slips into (2,0). The slip is believed and robot 0's move is taken back (told to stay), so it
// does not drive into robot 1. (Before, robot 1 was marked inconsistent for as long as it stayed
// there, and robot 0 kept its command into the cell robot 1 stands in.) Then both go on.
TEST(ExecutorAdg, ASlipIntoACellCommandedToARobotAtRestTakesThatMoveBack) {
  const Grid g = Grid::from_rows({"......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 2, &fn);
  Executor ex(g, dist, 2, ExecutorConfig{});
  std::vector<RobotRecord> robots{at(g, 1, 0), at(g, 3, 0)};
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    if (w.positions[0] == g.cell(1, 0)) next[0] = g.cell(2, 0);
    if (w.positions[1] == g.cell(2, 0)) next[1] = g.cell(3, 0);
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(2, 0));
  robots[1] = at(g, 2, 0);  // slipped; robot 0 is delayed, at rest in (1,0)
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[1], RobotHealth::kOk) << "the slip into a cell nobody is in or entering is believed";
  EXPECT_EQ(ex.cell(1), g.cell(2, 0));
  EXPECT_NE(out.command[0], g.cell(2, 0)) << "robot 0 is still sent into the cell robot 1 slipped into";
  EXPECT_EQ(out.command[0], g.cell(1, 0));
  EXPECT_EQ(out.command[1], g.cell(3, 0)) << "robot 1 goes on from where it is";
  EXPECT_EQ(ex.check_invariants(), "");
  robots[1] = at(g, 3, 0);  // arrived: robot 0 may now enter (2,0)
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(2, 0));
  EXPECT_EQ(ex.check_invariants(), "");
}

// Issue 25: robot 1 reports the cell robot 0 stands in: not believed (an obstacle at both cells).
// It is told to stay where it reports, not sent on. Once robot 0 has left, robot 1's report of that
// cell, next to its own, is believed and it is planned again. (Before, the same report stayed
// inconsistent for ever: the robot was never planned again.)
TEST(ExecutorAdg, ARobotReportingAnOccupiedNeighbourIsBelievedOnceTheCellIsFree) {
  const Grid g = Grid::from_rows({"......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 2, &fn);
  Executor ex(g, dist, 2, ExecutorConfig{});
  std::vector<RobotRecord> robots{at(g, 2, 0), at(g, 3, 0)};
  bool leave = false;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    if (leave && w.positions[0] == g.cell(2, 0)) next[0] = g.cell(1, 0);
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  robots[1] = at(g, 2, 0);  // robot 0 is there
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[1], RobotHealth::kInconsistent);
  EXPECT_EQ(out.command[1], g.cell(2, 0)) << "told to stay where it reports";
  leave = true;
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(1, 0));
  robots[0] = at(g, 1, 0);  // robot 0 has left (2,0)
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[1], RobotHealth::kOk) << "robot 1 stays inconsistent although its report now fits";
  EXPECT_EQ(ex.cell(1), g.cell(2, 0));
  EXPECT_EQ(ex.check_invariants(), "");
}

// Issue 25: robot 1, commanded from (3,0) into (4,0), reports (1,0), where robot 0 stands, three
// cells from the cell it was sent to: it is told to stay where it reports (not sent on to (4,0),
// which is not next to it); reporting so while moving, it gets no command at all.
TEST(ExecutorAdg, AnInconsistentRobotIsToldToStayWhereItReports) {
  const Grid g = Grid::from_rows({"......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 2, &fn);
  Executor ex(g, dist, 2, ExecutorConfig{});
  std::vector<RobotRecord> robots{at(g, 1, 0), at(g, 3, 0)};
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    if (w.positions[1] == g.cell(3, 0)) next[1] = g.cell(4, 0);
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[1], g.cell(4, 0));
  robots[1] = at(g, 1, 0);
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[1], RobotHealth::kInconsistent);
  EXPECT_EQ(out.command[1], g.cell(1, 0)) << "sent to " << g.describe(out.command[1]);
  robots[1].moving = true;
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[1], kNoCell) << "sent to " << g.describe(out.command[1]);
  EXPECT_EQ(ex.check_invariants(), "");
}

// Issue 25: between ticks, robot 0 leaves (2,0) and robot 1, queued behind it, would be sent in;
// but robot 2 reports it has slipped into (2,0). Nobody is sent into a cell a robot reports being
// in: robot 1 waits, and the next tick takes robot 2's slip and plans robot 1 again. (Before,
// reports that were not arrivals were ignored between ticks and robot 1 was sent into robot 2.)
TEST(ExecutorAdg, NoDispatchBetweenTicksIntoACellARobotReportsBeingIn) {
  const Grid g = Grid::from_rows({"......", "......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 3, &fn);
  Executor ex(g, dist, 3, ExecutorConfig{});
  std::vector<RobotRecord> robots{at(g, 2, 0), at(g, 1, 0), at(g, 2, 1)};
  int step = 0;
  fn->fn = [&](const gdrhcr::WorldView&, std::vector<Cell>& next) {
    if (step++ == 0) next[0] = g.cell(3, 0), next[1] = g.cell(2, 0);
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(3, 0));
  EXPECT_EQ(out.waiting, 1);
  robots[0] = at(g, 3, 0);  // arrived
  robots[2] = at(g, 2, 0);  // slipped into the cell robot 0 left
  EXPECT_TRUE(ex.advance(robots).empty());
  EXPECT_EQ(ex.command(1), g.cell(1, 0));
  EXPECT_EQ(ex.cell(0), g.cell(3, 0)) << "the arrival is taken";
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[2], RobotHealth::kOk);
  EXPECT_EQ(ex.cell(2), g.cell(2, 0));
  EXPECT_EQ(out.command[1], g.cell(1, 0));
  EXPECT_TRUE(ex.committed(1).empty()) << "robot 1's move into (2,0) is planned again";
  EXPECT_EQ(ex.check_invariants(), "");
}

// Issue 25 (the one-hour night shift's collision): robot 0, commanded into (2,0), slips towards
// (1,1) and says so (RobotRecord::entering) while still in (1,0). From that report on, nobody is
// sent into (1,1): robot 1's planned move there becomes a wait and robot 0 gets no command until it
// stops. Once it reports (1,1) at rest, it is believed and planned from there. (Before, the cell a
// slipping robot entered was free for everybody until it arrived, and robot 1 was sent into it.)
TEST(ExecutorAdg, ACellARobotReportsSlippingIntoIsKeptClearAtOnce) {
  const Grid g = Grid::from_rows({"......", "......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 2, &fn);
  Executor ex(g, dist, 2, ExecutorConfig{});
  std::vector<RobotRecord> robots{at(g, 1, 0), at(g, 2, 1)};
  int step = 0;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    if (step++ == 0) next[0] = g.cell(2, 0);
    else if (w.positions[1] == g.cell(2, 1)) next[1] = g.cell(1, 1);  // unaware of the slip
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(2, 0));
  robots[0] = at(g, 1, 0, true);
  robots[0].entering = g.cell(1, 1);
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[0], RobotHealth::kInconsistent);
  EXPECT_NE(out.command[1], g.cell(1, 1)) << "robot 1 is sent into the cell robot 0 is slipping into";
  EXPECT_EQ(out.command[0], kNoCell) << "a robot moving where it was not sent gets no command until it stops";
  EXPECT_EQ(ex.check_invariants(), "");
  out = ex.tick(robots, stay_goals(robots), *planner, false);  // still under way: still kept clear
  EXPECT_NE(out.command[1], g.cell(1, 1));
  robots[0] = at(g, 1, 1);
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[0], RobotHealth::kOk);
  EXPECT_EQ(ex.cell(0), g.cell(1, 1));
  EXPECT_NE(out.command[1], g.cell(1, 1));
  EXPECT_EQ(ex.check_invariants(), "");
}

// Issue 25: between ticks, robot 2 leaves (2,1) and robot 1, queued behind it, would be sent in;
// in the same report robot 0 (commanded into (3,0)) says it is slipping into (2,1). Nobody is sent
// into a cell a robot reports entering: robot 1 waits, and the next tick takes robot 0's slip.
TEST(ExecutorAdg, NoDispatchBetweenTicksIntoACellARobotReportsSlippingInto) {
  const Grid g = Grid::from_rows({"......", "......"});
  gdrhcr::DistTable dist(g);
  FnPlanner* fn;
  auto planner = make_fn_planner(g, 3, &fn);
  Executor ex(g, dist, 3, ExecutorConfig{});
  std::vector<RobotRecord> robots{at(g, 2, 0), at(g, 1, 1), at(g, 2, 1)};
  int step = 0;
  fn->fn = [&](const gdrhcr::WorldView&, std::vector<Cell>& next) {
    if (step++ == 0) next[0] = g.cell(3, 0), next[1] = g.cell(2, 1), next[2] = g.cell(3, 1);
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(3, 0));
  EXPECT_EQ(out.command[2], g.cell(3, 1));
  EXPECT_EQ(out.waiting, 1);
  robots[2] = at(g, 3, 1);  // arrived
  robots[0] = at(g, 2, 0, true);
  robots[0].entering = g.cell(2, 1);  // slipping into the cell robot 2 left
  EXPECT_TRUE(ex.advance(robots).empty());
  EXPECT_EQ(ex.command(1), g.cell(1, 1));
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[0], RobotHealth::kInconsistent);
  EXPECT_EQ(out.command[1], g.cell(1, 1));
  EXPECT_EQ(ex.check_invariants(), "");
}

namespace {

// Robot i, at rest and not delayed, slips into a neighbour no robot is in or entering: one another
// robot was commanded into and has not started for when there is one (it is delayed), else any.
// Returns true when it slipped.
bool slip(DelayedFleet& sim, size_t i) {
  auto& r = sim.robots();
  SimRobot& s = r[i];
  if (s.missing || s.silent || s.offline || s.moving || s.delay > 0) return false;
  Cell best = kNoCell;
  for (Cell nb : small_warehouse().neighbours(s.cell)) {
    bool taken = false, commanded = false;
    for (const SimRobot& o : r) {
      if (o.missing) continue;
      taken |= o.cell == nb || (o.moving && o.dst == nb);
      commanded |= !o.moving && o.cmd == nb;
    }
    if (taken) continue;
    if (best == kNoCell || commanded) best = nb;
    if (commanded) break;
  }
  if (best == kNoCell) return false;
  s.cell = best;
  s.cmd = kNoCell;  // its controller drops the move it was given
  return true;
}

}  // namespace

// Issue 25: slips, faults and planner restarts together, with two moves committed ahead and moves
// dispatched between ticks (the node's defaults), under random delays. Every few ticks a robot
// slips into a free neighbour, preferably one another robot was commanded into and has not started
// for (it is delayed); robot 1 falls silent mid-run and comes back, robot 2 goes offline and comes
// back (offline across a restart); twice the planner process restarts (a fresh executor and planner, robots mid-move). No two
// robots ever share a cell, no command is bad, and after 60 ticks without delays or faults every
// robot is healthy again, moving, and the fleet reaches goals.
TEST(ExecutorAdg, SlipsFaultsAndRestartsWithTwoMovesAheadAndDispatchOnArrival) {
  for (uint64_t seed = 1; seed <= seeds(8); ++seed) {
    int slips = 0;
    auto faults = [&](int t, DelayedFleet& sim) {
      auto& r = sim.robots();
      if (t == 20) r[1].silent = true;  // back before the restart: a restarted node never hears of a silent robot
      if (t == 50) r[1].silent = false;
      if (t == 35) r[2].offline = true;
      if (t == 85) r[2].offline = false;
      if (t < 150 && t % 4 == 0)
        for (size_t k = 0; k < r.size(); ++k)
          if (slip(sim, (t / 4 + k * 7) % r.size())) {
            ++slips;
            break;
          }
    };
    for (const char* planner : {"pibt", "gd-rhcr"}) {
      if (std::string(planner) == "gd-rhcr" && seed > 3) continue;
      slips = 0;
      const SimResult res = run_fleet(planner, 30, seed, 150, 60, 0.05, 20, faults, 2, true, {60, 120});
      if (HasFailure()) return;
      EXPECT_GT(slips, 20) << planner << " seed " << seed;
      EXPECT_GT(res.goals_tail, 0) << planner << " seed " << seed;
      EXPECT_LE(res.max_wait_tail, 30) << planner << " seed " << seed;
      for (int i = 0; i < 30; ++i)
        EXPECT_EQ(res.final_health[i], RobotHealth::kOk) << planner << " seed " << seed << " robot " << i;
      EXPECT_GT(res.health_ticks[1][int(RobotHealth::kSilent)], 0);
      EXPECT_GT(res.health_ticks[2][int(RobotHealth::kOffline)], 0);
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Turning robots (issue 23): the rotation action model, and mapf plans executed by robots that
// turn.

namespace {

RobotRecord facing(const Grid& g, int x, int y, gdrhcr::Heading h, bool moving = false) {
  RobotRecord r = at(g, x, y, moving);
  r.heading = h;
  return r;
}

std::unique_ptr<DeadlinePlanner> make_fn_planner_rotation(const Grid& g, int n, FnPlanner** out) {
  auto p = std::make_unique<FnPlanner>();
  *out = p.get();
  gdrhcr::Params none;
  return std::make_unique<DeadlinePlanner>(std::move(p),
                                           gdrhcr::make_planner("pibt", none, g, n, 1, gdrhcr::ActionModel::kRotation));
}

struct TurnResult {
  int goals_tail = 0, turns = 0, turns_before_moves = 0, caught_up = 0;
};

// run_fleet's loop with turning robots (DelayedFleet::give_headings: a quarter turn takes a move's
// time): `model` is the planner's and the executor's. In the rotation model a robot must never be
// sent forward into a cell it does not face (DelayedFleet reports it as a bad command).
TurnResult run_turning(gdrhcr::ActionModel model, const std::string& planner_name, int n, uint64_t seed, int ticks,
                       int tail, double p_delay, bool between, int catch_up = 0) {
  const Grid& g = small_warehouse();
  gdrhcr::DistTable dist(g, model);
  gdrhcr::Params params, none;
  if (planner_name == "gd-rhcr") params.set("timeout", "1"), params.set("node-budget", "2000");
  ExecutorConfig cfg;
  cfg.commit_horizon = 2;
  cfg.action_model = model;
  cfg.catch_up = catch_up;
  DeadlinePlanner planner(gdrhcr::make_planner(planner_name, params, g, n, seed, model),
                          gdrhcr::make_planner("pibt", none, g, n, seed, model));
  Executor ex(g, dist, n, cfg);
  DelayedFleet sim(g, n, seed);
  sim.give_headings(model == gdrhcr::ActionModel::kRotation);
  DelayedFleet::Between on_arrival = [&](const std::vector<RobotRecord>& reports) {
    auto cmds = DelayedFleet::on_arrival(ex)(reports);
    EXPECT_EQ(ex.check_invariants(), "");
    return cmds;
  };
  TurnResult res;
  for (int t = 0; t < ticks + tail; ++t) {
    int reached = 0;
    auto goals = sim.goals(reached);
    if (t >= ticks) res.goals_tail += reached;
    auto out = ex.tick(sim.records(), goals, planner, true);
    EXPECT_TRUE(out.stepped) << out.skip_reason;
    EXPECT_EQ(out.plan_error, "") << "seed " << seed << " tick " << t;
    EXPECT_EQ(ex.check_invariants(), "") << "seed " << seed << " tick " << t;
    res.caught_up += out.caught_up;
    const std::string bad = sim.execute(out, t < ticks ? p_delay : 0.0, 20, between ? on_arrival : nullptr);
    if (!bad.empty() || ::testing::Test::HasFailure()) {
      ADD_FAILURE() << bad << " (" << planner_name << " " << gdrhcr::action_model_name(model) << " seed " << seed
                    << " tick " << t << ")";
      return res;
    }
  }
  for (const SimRobot& s : sim.robots()) res.turns += s.turns, res.turns_before_moves += s.turns_before_moves;
  return res;
}

}  // namespace

// Robot 0 turns in (1,0) before it goes on east; robot 1 is to follow it into (1,0). The turn is
// commanded at once and is late: robot 0's cell stays its own (robot 1's move into it is held,
// robot 1 is not sent there), robot 0's forward move is sent only once it reports the new heading,
// and robot 1's move into (1,0), committed while robot 0 leaves it, is sent only once robot 0 has
// arrived in (2,0).
TEST(ExecutorRotation, ATurningRobotKeepsItsCellAndMovesForwardOnlyOnceTurned) {
  const Grid g = Grid::from_rows({"....."});
  gdrhcr::DistTable dist(g, gdrhcr::ActionModel::kRotation);
  FnPlanner* fn;
  auto planner = make_fn_planner_rotation(g, 2, &fn);
  ExecutorConfig cfg;
  cfg.action_model = gdrhcr::ActionModel::kRotation;
  cfg.commit_horizon = 3;
  Executor ex(g, dist, 2, cfg);
  std::vector<RobotRecord> robots{facing(g, 1, 0, gdrhcr::kNorth), facing(g, 0, 0, gdrhcr::kEast)};
  int step = 0;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    ASSERT_TRUE(w.rotation());
    if (step == 0) (*w.next_headings)[0] = gdrhcr::kEast;  // a quarter turn clockwise
    if (step == 1) {
      EXPECT_EQ((*w.headings)[0], gdrhcr::kEast) << "planned from the committed heading";
      next[0] = g.cell(2, 0);
      next[1] = g.cell(1, 0);  // follows robot 0 out of (1,0), whose turn is late: held
    }
    if (step >= 2 && w.positions[1] == g.cell(0, 0)) next[1] = g.cell(1, 0);
    ++step;
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.command[0], g.cell(1, 0));
  EXPECT_EQ(out.command_heading[0], gdrhcr::kEast);
  EXPECT_EQ(command_action({ex.cell(0), ex.heading(0)}, out.command[0], out.command_heading[0]),
            gdrhcr::Action::kClockwise);
  out = ex.tick(robots, stay_goals(robots), *planner, false);  // robot 0 still faces north: late
  EXPECT_EQ(out.plan_error, "");
  EXPECT_EQ(out.held, 1) << "robot 1's move into the cell robot 0 turns in was not held";
  EXPECT_EQ(out.command[0], g.cell(1, 0));
  EXPECT_EQ(out.command_heading[0], gdrhcr::kEast);
  EXPECT_EQ(out.command[1], g.cell(0, 0));
  EXPECT_EQ(ex.committed(0), (std::vector<Cell>{g.cell(1, 0), g.cell(2, 0)}));
  EXPECT_TRUE(ex.committed(1).empty());
  EXPECT_EQ(ex.check_invariants(), "");
  EXPECT_TRUE(ex.advance(robots).empty()) << "a forward move was sent before the turn was done";
  robots[0].heading = gdrhcr::kEast;  // the turn is done: its forward move goes at once
  EXPECT_EQ(ex.advance(robots), std::vector<int>{0});
  EXPECT_EQ(ex.command(0), g.cell(2, 0));
  EXPECT_EQ(ex.command_heading(0), gdrhcr::kEast);
  EXPECT_EQ(command_action({ex.cell(0), ex.heading(0)}, ex.command(0), ex.command_heading(0)), gdrhcr::Action::kForward);
  robots[0].moving = true;
  out = ex.tick(robots, stay_goals(robots), *planner, false);  // robot 1's follow move is committed, waits
  EXPECT_EQ(ex.committed(1), std::vector<Cell>{g.cell(1, 0)});
  EXPECT_EQ(out.command[1], g.cell(0, 0));
  EXPECT_EQ(out.waiting, 1);
  EXPECT_TRUE(ex.advance(robots).empty());
  robots[0] = facing(g, 2, 0, gdrhcr::kEast);  // arrived: now robot 1 may enter (1,0)
  EXPECT_EQ(ex.advance(robots), std::vector<int>{1});
  EXPECT_EQ(ex.command(1), g.cell(1, 0));
  EXPECT_EQ(ex.check_invariants(), "");
}

// A heading nobody commanded is believed: the robot's undispatched commitments are dropped and it
// is planned from its real pose; a report without a heading makes it an obstacle.
TEST(ExecutorRotation, AHeadingNobodyCommandedIsReplannedFromThere) {
  const Grid g = Grid::from_rows({"....."});
  gdrhcr::DistTable dist(g, gdrhcr::ActionModel::kRotation);
  FnPlanner* fn;
  auto planner = make_fn_planner_rotation(g, 1, &fn);
  ExecutorConfig cfg;
  cfg.action_model = gdrhcr::ActionModel::kRotation;
  cfg.commit_horizon = 3;
  Executor ex(g, dist, 1, cfg);
  std::vector<RobotRecord> robots{facing(g, 2, 0, gdrhcr::kEast)};
  std::vector<gdrhcr::Heading> seen;
  fn->fn = [&](const gdrhcr::WorldView& w, std::vector<Cell>& next) {
    seen.push_back((*w.headings)[0]);
    next[0] = w.positions[0];
  };
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  robots[0].heading = gdrhcr::kWest;  // turned on its own (a half turn)
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.resyncs, 1);
  EXPECT_EQ(out.health[0], RobotHealth::kOk);
  EXPECT_EQ(seen.back(), gdrhcr::kWest);
  EXPECT_EQ(out.command_heading[0], gdrhcr::kWest);
  robots[0].heading = gdrhcr::kNoHeading;
  out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.health[0], RobotHealth::kInconsistent);
  ASSERT_FALSE(out.warnings.empty());
  EXPECT_NE(out.warnings.back().find("no heading"), std::string::npos) << out.warnings.back();
}

// A distance table in another action model than the robots' is refused, naming both.
TEST(ExecutorRotation, ADistanceTableInAnotherModelIsRefused) {
  const Grid g = Grid::from_rows({"..."});
  gdrhcr::DistTable dist(g);
  ExecutorConfig cfg;
  cfg.action_model = gdrhcr::ActionModel::kRotation;
  try {
    Executor ex(g, dist, 1, cfg);
    FAIL() << "accepted a mapf table for rotation robots";
  } catch (const gdrhcr::ParamError& e) {
    EXPECT_NE(std::string(e.what()).find("mapf"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rotation"), std::string::npos) << e.what();
  }
}

// The rotation model under random delays with robots that take a move's time per quarter turn:
// PIBT and GD-RHCR plan with turns, moves are dispatched on arrival, no two robots ever share a
// cell, no robot is sent into a cell it does not face, robots turn, and after the delays stop the
// fleet reaches goals again.
TEST(ExecutorRotation, DelayedTurningRobotsNeverCollideNorDeadlock) {
  for (uint64_t seed = 1; seed <= seeds(6); ++seed) {
    for (const char* planner : {"pibt", "gd-rhcr"}) {
      if (std::string(planner) == "gd-rhcr" && seed > 3) continue;
      const TurnResult r = run_turning(gdrhcr::ActionModel::kRotation, planner, 24, seed, 120, 60, 0.05, true);
      if (HasFailure()) return;
      EXPECT_GT(r.goals_tail, 0) << planner << " seed " << seed;
      EXPECT_GT(r.turns, 0) << planner << " seed " << seed;
      EXPECT_EQ(r.turns_before_moves, 0) << planner << " seed " << seed;
    }
  }
}

// The same with catch-up: robots owed steps make extra forward moves (never a turn, and never into
// a cell they do not face, which the simulated robots would report as a bad command).
TEST(ExecutorRotation, DelayedTurningRobotsNeverCollideNorDeadlock_CatchUp) {
  for (uint64_t seed = 1; seed <= seeds(4); ++seed) {
    const TurnResult r = run_turning(gdrhcr::ActionModel::kRotation, "gd-rhcr", 24, seed, 120, 60, 0.05, true, 100);
    if (HasFailure()) return;
    EXPECT_GT(r.goals_tail, 0) << "seed " << seed;
    EXPECT_GT(r.caught_up, 0) << "seed " << seed;
    EXPECT_EQ(r.turns_before_moves, 0) << "seed " << seed;
  }
}

// Catch-up in the rotation model, step by step: robot 0 faces east and is planned to wait at
// step 1; owed that step, it makes up the forward move east at once. Robot 1 faces north, and
// the cell its planner means it to enter next is east: a turn would be needed, so no extra move.
TEST(ExecutorRotation, CatchUpMakesUpForwardMovesOnly) {
  const Grid g = Grid::from_rows({"......", "......"});
  gdrhcr::DistTable dist(g, gdrhcr::ActionModel::kRotation);
  FnPlanner* fn;
  auto planner = make_fn_planner_rotation(g, 2, &fn);
  ExecutorConfig cfg;
  cfg.action_model = gdrhcr::ActionModel::kRotation;
  cfg.commit_horizon = 2;
  cfg.catch_up = 100;
  Executor ex(g, dist, 2, cfg);
  std::vector<RobotRecord> robots{facing(g, 0, 0, gdrhcr::kEast), facing(g, 0, 1, gdrhcr::kNorth)};
  fn->fn = [&](const gdrhcr::WorldView&, std::vector<Cell>&) {};  // both planned to wait
  fn->intends = [&](int, Cell c) { return c + 1; };                // east
  auto out = ex.tick(robots, stay_goals(robots), *planner, false);
  EXPECT_EQ(out.plan_error, "");
  EXPECT_EQ(out.caught_up, 1);
  EXPECT_EQ(out.command[0], g.cell(1, 0));
  EXPECT_EQ(out.command_heading[0], gdrhcr::kEast);
  EXPECT_EQ(command_action({ex.cell(0), ex.heading(0)}, out.command[0], out.command_heading[0]), gdrhcr::Action::kForward);
  EXPECT_TRUE(ex.committed(1).empty()) << "robot 1 would have to turn: nothing made up";
  EXPECT_EQ(out.command[1], g.cell(0, 1));
  EXPECT_EQ(out.command_heading[1], gdrhcr::kNorth);
  EXPECT_EQ(ex.check_invariants(), "");
}

// Mapf plans executed by turning robots: a move's command carries its heading, the robot turns
// before it moves (and, waiting for its next committed move, turns towards it meanwhile); no
// collision, no deadlock.
TEST(ExecutorRotation, MapfPlansExecutedByTurningRobots) {
  for (uint64_t seed = 1; seed <= seeds(4); ++seed) {
    const TurnResult r = run_turning(gdrhcr::ActionModel::kMapf, "pibt", 24, seed, 120, 60, 0.05, true);
    if (HasFailure()) return;
    EXPECT_GT(r.goals_tail, 0) << "seed " << seed;
    EXPECT_GT(r.turns, 0) << "seed " << seed;
  }
}
