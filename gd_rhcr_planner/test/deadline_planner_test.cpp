// DeadlinePlanner: a primary that misses the deadline is replaced by the fallback for that tick
// (and for later ticks while it is still busy); its late step is discarded; a throwing primary
// also falls back. The slow primary here blocks on a gate the test opens, so no outcome depends
// on the machine's speed.
#include <gtest/gtest.h>

#include <atomic>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "gd_rhcr_planner/deadline_planner.hpp"
#include "gdrhcr/validator.hpp"

using namespace gd_rhcr_planner;
using gdrhcr::Cell;
using gdrhcr::Grid;

namespace {

struct Gate {
  std::mutex m;
  std::condition_variable cv;
  bool open = false;
  void release() {
    std::lock_guard<std::mutex> l(m);
    open = true;
    cv.notify_all();
  }
  void wait() {
    std::unique_lock<std::mutex> l(m);
    cv.wait(l, [this] { return open; });
  }
};

// Moves every agent one cell right when it can; blocks on the gate first when one is given;
// throws when asked to.
class ScriptedPlanner : public gdrhcr::Planner {
 public:
  Gate* gate = nullptr;
  bool throw_now = false;
  std::atomic<int> calls{0};
  std::atomic<int>* finished = nullptr;  // counts completed steps; outlives the planner
  std::vector<uint8_t> seen_immovable;    // what the last call saw of WorldView::immovable
  std::string name() const override { return "scripted"; }
  gdrhcr::StepReport plan_step(const gdrhcr::WorldView& w, std::vector<Cell>& next) override {
    ++calls;
    if (gate) gate->wait();
    if (throw_now) throw std::runtime_error("scripted failure");
    seen_immovable = w.immovable ? *w.immovable : std::vector<uint8_t>{};
    for (int i = 0; i < w.num_agents(); ++i) {
      const int x = w.grid.x_of(w.positions[i]) + 1, y = w.grid.y_of(w.positions[i]);
      next[i] = w.grid.in_bounds(x, y) && w.grid.is_free(w.grid.cell(x, y)) ? w.grid.cell(x, y) : w.positions[i];
    }
    if (finished) ++*finished;
    return {true, 0.5};
  }
  nlohmann::json params() const override { return nlohmann::json::object(); }
};

struct World {
  Grid grid = Grid::from_rows({"........", "........"});
  gdrhcr::DistTable dist{grid};
  std::vector<Cell> pos{grid.cell(0, 0), grid.cell(0, 1)};
  std::vector<std::vector<Cell>> goals{{grid.cell(7, 1)}, {grid.cell(7, 0)}};
};

std::unique_ptr<gdrhcr::Planner> pibt(const Grid& g) {
  gdrhcr::Params none;
  return gdrhcr::make_planner("pibt", none, g, 2, 1);
}

}  // namespace

TEST(DeadlinePlanner, UsesThePrimaryWhenItAnswersInTime) {
  World w;
  auto primary = std::make_unique<ScriptedPlanner>();
  auto* p = primary.get();
  DeadlinePlanner dp(std::move(primary), pibt(w.grid));
  std::vector<Cell> next = w.pos;
  auto out = dp.step({w.grid, w.dist, 0, w.pos, w.goals}, next, 0);  // no deadline
  EXPECT_FALSE(out.fallback);
  EXPECT_DOUBLE_EQ(out.report.plan_time_s, 0.5);
  EXPECT_EQ(next[0], w.grid.cell(1, 0));
  EXPECT_EQ(next[1], w.grid.cell(1, 1));
  EXPECT_EQ(p->calls, 1);
  EXPECT_TRUE(dp.primary_idle());
}

TEST(DeadlinePlanner, FallsBackWhileThePrimaryIsLateAndDiscardsItsLateStep) {
  World w;
  Gate gate;
  auto primary = std::make_unique<ScriptedPlanner>();
  auto* p = primary.get();
  p->gate = &gate;
  DeadlinePlanner dp(std::move(primary), pibt(w.grid));
  gdrhcr::StepValidator validator(w.grid);
  std::vector<Cell> next = w.pos;
  auto out = dp.step({w.grid, w.dist, 0, w.pos, w.goals}, next, 0.01);  // the gate is shut
  EXPECT_TRUE(out.fallback);
  EXPECT_TRUE(out.primary_late);
  EXPECT_FALSE(validator.check(w.pos, next)) << "fallback step collides";
  EXPECT_NE(next, w.pos) << "the fallback moved nobody towards the goals";
  EXPECT_FALSE(dp.primary_idle());
  // Next tick: the primary is still on the abandoned step; the fallback answers at once.
  w.pos = next;
  out = dp.step({w.grid, w.dist, 1, w.pos, w.goals}, next, 10.0);
  EXPECT_TRUE(out.fallback);
  EXPECT_TRUE(out.primary_busy);
  EXPECT_EQ(p->calls, 1);
  gate.release();
  dp.wait_idle();
  // Once free, the primary plans again from the positions it is given now.
  w.pos = next;
  out = dp.step({w.grid, w.dist, 2, w.pos, w.goals}, next, 0);
  EXPECT_FALSE(out.fallback);
  EXPECT_EQ(p->calls, 2);
  EXPECT_EQ(next[0], w.grid.cell(w.grid.x_of(w.pos[0]) + 1, w.grid.y_of(w.pos[0])));
}

TEST(DeadlinePlanner, TheWorkerSeesTheImmovableAgentsAndKeepsTheDistTableAlive) {
  World w;
  auto primary = std::make_unique<ScriptedPlanner>();
  auto* p = primary.get();
  DeadlinePlanner dp(std::move(primary), pibt(w.grid));
  std::vector<uint8_t> immovable = {0, 1};
  auto dist = std::make_shared<const gdrhcr::DistTable>(w.grid, std::vector<Cell>{w.pos[1]});
  std::weak_ptr<const gdrhcr::DistTable> watch = dist;
  gdrhcr::WorldView world{w.grid, *dist, 0, w.pos, w.goals};
  world.immovable = &immovable;
  std::vector<Cell> next = w.pos;
  auto out = dp.step(world, next, 0, dist);
  EXPECT_FALSE(out.fallback);
  EXPECT_EQ(p->seen_immovable, immovable);
  dist.reset();
  EXPECT_TRUE(watch.expired()) << "the finished step still holds the DistTable";
}

TEST(DeadlinePlanner, FallsBackWhenThePrimaryThrows) {
  World w;
  auto primary = std::make_unique<ScriptedPlanner>();
  primary->throw_now = true;
  DeadlinePlanner dp(std::move(primary), pibt(w.grid));
  std::vector<Cell> next = w.pos;
  auto out = dp.step({w.grid, w.dist, 0, w.pos, w.goals}, next, 0);
  EXPECT_TRUE(out.fallback);
  EXPECT_EQ(out.primary_error, "scripted failure");
  EXPECT_FALSE(out.primary_late);
}

TEST(DeadlinePlanner, DestructionWaitsForAnAbandonedStep) {
  World w;
  Gate gate;
  std::atomic<int> finished{0};
  auto primary = std::make_unique<ScriptedPlanner>();
  primary->gate = &gate;
  primary->finished = &finished;
  std::vector<Cell> next = w.pos;
  std::thread opener;
  {
    DeadlinePlanner dp(std::move(primary), pibt(w.grid));
    EXPECT_TRUE(dp.step({w.grid, w.dist, 0, w.pos, w.goals}, next, 0.001).primary_late);
    opener = std::thread([&] { gate.release(); });
  }  // the destructor waits for the worker to finish its step (else a use after free)
  opener.join();
  EXPECT_EQ(finished, 1);
}
