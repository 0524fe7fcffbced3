// TaskStore: accepted tasks survive a restart (journal replay into a new Fleet, with assigned
// and picked tasks back on their robots), compaction keeps the store readable and bounded, a
// torn last line is tolerated, damage elsewhere is an error naming the file and line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "fleet_fixtures.hpp"
#include "gd_rhcr_planner/task_store.hpp"

using namespace gd_rhcr_planner;
using namespace gd_rhcr_planner::fixtures;
using gdrhcr::Grid;

namespace {
struct TempDir {
  std::filesystem::path dir;
  TempDir() {
    dir = std::filesystem::temp_directory_path() /
          ("gd_rhcr_store_" + std::to_string(::getpid()) + "_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir);
  }
  ~TempDir() { std::filesystem::remove_all(dir); }
  std::string file() const { return (dir / "sub" / "tasks.jsonl").string(); }
};
void flush(Fleet& f, TaskStore& s) { s.record(f.take_events(), f); }
}  // namespace

TEST(TaskStore, TasksSurviveARestartWithTheirRobots) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  TempDir tmp;
  uint64_t queued_id, assigned_id, picked_id, done_id;
  {
    Fleet f(g, d, 3);
    TaskStore store(tmp.file());  // creates the directory
    EXPECT_TRUE(store.loaded().open.empty());
    ASSERT_EQ(report(f, 0, 0, 0), "");
    ASSERT_EQ(report(f, 1, 9, 0), "");
    ASSERT_EQ(report(f, 2, 0, 2), "");
    done_id = f.submit(0, 2, 3, 2, 9).task_id;     // robot 2 stands on its pickup
    picked_id = f.submit(9, 0, 0, 2, 5).task_id;   // robot 1 stands on its pickup
    assigned_id = f.submit(5, 0, 9, 2, 4).task_id;  // robot 0, on its way
    f.advance();
    flush(f, store);
    ASSERT_EQ(report(f, 2, 3, 2), "");  // delivers
    f.advance();
    queued_id = f.submit(4, 2, 0, 0, 0).task_id;  // robot 2 is idle again: gets it
    std::string reason;
    const uint64_t cancelled = f.submit(6, 2, 0, 0, 0).task_id;
    ASSERT_TRUE(f.cancel(cancelled, reason));
    f.advance();
    flush(f, store);
    ASSERT_EQ(f.task(picked_id)->state, kPicked);
    ASSERT_EQ(f.task(assigned_id)->robot, 0);
    ASSERT_EQ(f.task(queued_id)->state, kAssigned);
    ASSERT_EQ(f.task(queued_id)->robot, 2);
    ASSERT_EQ(f.delivered_total(), 1u);
  }  // the node dies here
  TaskStore store(tmp.file());
  const auto& loaded = store.loaded();
  ASSERT_EQ(loaded.open.size(), 3u);
  EXPECT_EQ(loaded.delivered, 1u);
  Fleet f(g, d, 3);
  EXPECT_EQ(f.restore(loaded.open, loaded.delivered, loaded.failed, loaded.next_id), 3u);
  EXPECT_EQ(f.delivered_total(), 1u);
  EXPECT_EQ(f.task(picked_id)->state, kPicked);
  EXPECT_EQ(f.task(picked_id)->robot, 1);
  EXPECT_EQ(f.task_of(1), static_cast<int64_t>(picked_id));
  EXPECT_EQ(f.task(assigned_id)->robot, 0);
  EXPECT_EQ(f.task(queued_id)->robot, 2);
  EXPECT_EQ(f.task(done_id), nullptr);
  // Robots resume: robot 1 reaches the delivery of the task it carried.
  ASSERT_EQ(report(f, 0, 5, 0), "");
  ASSERT_EQ(report(f, 1, 0, 2), "");
  ASSERT_EQ(report(f, 2, 4, 2), "");
  f.advance();
  EXPECT_EQ(f.task(picked_id)->state, kDelivered);
  EXPECT_EQ(f.task(assigned_id)->state, kPicked);
  EXPECT_EQ(f.delivered_total(), 2u);
  // Fresh ids continue above every id the store has seen.
  EXPECT_GT(f.submit(1, 0, 2, 0, 0).task_id, queued_id + 1);
}

TEST(TaskStore, RestoredTasksAreCheckedAgainstTheMap) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  TaskRecord ok, blocked, foreign_robot;
  ok.id = 4, ok.pickup_x = 0, ok.pickup_y = 0, ok.delivery_x = 9, ok.delivery_y = 2, ok.state = kQueued;
  blocked = ok;
  blocked.id = 5, blocked.pickup_x = 3, blocked.pickup_y = 1;  // an obstacle on this map
  foreign_robot = ok;
  foreign_robot.id = 6, foreign_robot.state = kPicked, foreign_robot.robot = 17;  // no robot 17
  Fleet f(g, d, 2);
  EXPECT_EQ(f.restore({ok, blocked, foreign_robot}, 0, 0, 7), 2u);
  EXPECT_EQ(f.task(5)->state, kFailed);
  EXPECT_NE(f.task(5)->reason.find("obstacle"), std::string::npos) << f.task(5)->reason;
  EXPECT_EQ(f.task(6)->state, kQueued);
  EXPECT_EQ(f.task(6)->robot, -1);
}

TEST(TaskStore, CompactionKeepsTheJournalBoundedAndReadable) {
  Grid g = corridor();
  gdrhcr::DistTable d(g);
  TempDir tmp;
  Fleet f(g, d, 1);
  TaskStore store(tmp.file());
  ASSERT_EQ(report(f, 0, 0, 0), "");
  std::string reason;
  for (int i = 0; i < 3000; ++i) {  // 2 records per task: the journal must compact
    const auto id = f.submit(1, 0, 2, 0, 0).task_id;
    ASSERT_TRUE(f.cancel(id, reason));
    flush(f, store);
  }
  const auto open_id = f.submit(9, 2, 0, 2, 0).task_id;
  flush(f, store);
  EXPECT_LT(store.journal_lines(), 4200u);
  const auto back = TaskStore::read(tmp.file());
  ASSERT_EQ(back.open.size(), 1u);
  EXPECT_EQ(back.open[0].id, open_id);
  EXPECT_GT(back.next_id, open_id);
}

TEST(TaskStore, TornLastLineIsIgnoredDamageElsewhereIsAnError) {
  TempDir tmp;
  std::filesystem::create_directories(std::filesystem::path(tmp.file()).parent_path());
  const std::string rec =
      R"({"id":3,"pickup":[0,0],"delivery":[9,2],"priority":0,"state":0,"robot":-1})";
  {
    std::ofstream out(tmp.file());
    out << rec << "\n" << R"({"id":4,"pickup":[0,)";  // the crash hit mid-line
  }
  auto s = TaskStore::read(tmp.file());
  ASSERT_EQ(s.open.size(), 1u);
  EXPECT_EQ(s.open[0].id, 3u);
  ASSERT_EQ(s.warnings.size(), 1u);
  {
    std::ofstream out(tmp.file());
    out << rec << "\n" << "garbage\n" << rec << "\n";
  }
  try {
    TaskStore store(tmp.file());
    FAIL() << "a damaged store was accepted";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(tmp.file()), std::string::npos) << what;
    EXPECT_NE(what.find("line 2"), std::string::npos) << what;
  }
}
