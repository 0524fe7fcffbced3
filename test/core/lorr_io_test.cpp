// LoRR instances in and out: problem files parse, bad ones are rejected naming the file and the
// line or field, the task list runs in the Start-Kit's order, and the output JSON replays our
// own paths exactly (round trip through the JSON text).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "gdrhcr/lorr_io.hpp"
#include "gdrhcr/params.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;
namespace fs = std::filesystem;

namespace {
// A scratch folder with a LoRR problem: a 6 x 4 map with E/S cells and a wall, 3 agents, 5 tasks.
struct LorrFiles {
  fs::path dir;
  LorrFiles() {
    dir = fs::path(testing::TempDir()) / ("lorr_" + std::to_string(::getpid()) + "_" +
                                          testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir);
    fs::create_directories(dir / "maps");
    write("maps/small.map", "type octile\nheight 4\nwidth 6\nmap\nE....S\n.@@@..\n......\nS....E\n");
    write("agents.txt", "3\n0\n11\n23\n");
    write("tasks.txt", "5\n5\n18\n2\n12\n23\n");
    write("problem.json",
          "{\n  \"mapFile\": \"maps/small.map\",\n  \"agentFile\": \"agents.txt\",\n  \"teamSize\": 3,\n"
          "  \"taskFile\": \"tasks.txt\",\n  \"numTasksReveal\": 2,\n  \"taskAssignmentStrategy\": \"roundrobin\"\n}\n");
  }
  ~LorrFiles() { fs::remove_all(dir); }
  void write(const std::string& name, const std::string& text) const { std::ofstream(dir / name) << text; }
  std::string path(const std::string& name) const { return (dir / name).string(); }
};

std::string error_of(const std::string& problem) {
  try {
    load_lorr_problem(problem);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}
}  // namespace

TEST(LorrIo, ProblemParses) {
  LorrFiles f;
  LorrProblem p = load_lorr_problem(f.path("problem.json"));
  EXPECT_EQ(p.grid.width(), 6);
  EXPECT_EQ(p.grid.height(), 4);
  EXPECT_TRUE(p.grid.is_free(p.grid.cell(0, 0)));  // E
  EXPECT_TRUE(p.grid.is_free(p.grid.cell(5, 0)));  // S
  EXPECT_FALSE(p.grid.is_free(p.grid.cell(1, 1)));
  EXPECT_EQ(p.team_size, 3);
  EXPECT_EQ(p.num_tasks_reveal, 2);
  EXPECT_EQ(p.strategy, TaskListStream::Strategy::RoundRobin);
  // Linear ids are row * width + col: 11 = row 1, col 5; 23 = row 3, col 5.
  EXPECT_EQ(p.starts, (std::vector<Cell>{p.grid.cell(0, 0), p.grid.cell(5, 1), p.grid.cell(5, 3)}));
  EXPECT_EQ(p.tasks, (std::vector<Cell>{5, 18, 2, 12, 23}));
  // teamSize below the agent file's count takes the first agents; defaults apply.
  f.write("p2.json", R"({"mapFile": "maps/small.map", "agentFile": "agents.txt", "teamSize": 2, "taskFile": "tasks.txt"})");
  LorrProblem q = load_lorr_problem(f.path("p2.json"));
  EXPECT_EQ(q.starts.size(), 2u);
  EXPECT_EQ(q.num_tasks_reveal, 1);
  EXPECT_EQ(q.strategy, TaskListStream::Strategy::RoundRobin);
}

TEST(LorrIo, BadFilesAreRejectedNamingTheFileAndLineOrField) {
  LorrFiles f;
  const std::string problem = f.path("problem.json");
  auto expect_error = [&](const std::string& needle1, const std::string& needle2) {
    const std::string e = error_of(problem);
    EXPECT_NE(e.find(needle1), std::string::npos) << e;
    EXPECT_NE(e.find(needle2), std::string::npos) << e;
  };
  f.write("problem.json", "{\n  \"mapFile\": \"maps/small.map\",\n  \"agentFile\": agents.txt\n}\n");
  expect_error(problem + ":3:", "not valid JSON");
  f.write("problem.json", R"({"agentFile": "agents.txt", "teamSize": 3, "taskFile": "tasks.txt"})");
  expect_error(problem, "\"mapFile\" is missing");
  f.write("problem.json", R"({"mapFile": "maps/small.map", "agentFile": "agents.txt", "teamSize": "3", "taskFile": "tasks.txt"})");
  expect_error(problem, "\"teamSize\" must be an integer");
  f.write("problem.json", R"({"mapFile": "maps/small.map", "agentFile": "agents.txt", "teamSize": 4, "taskFile": "tasks.txt"})");
  expect_error(problem, "\"teamSize\" is 4");
  f.write("problem.json", R"({"mapFile": "maps/small.map", "agentFile": "agents.txt", "teamSize": 3, "taskFile": "tasks.txt", "taskAssignmentStrategy": "fifo"})");
  expect_error(problem, "taskAssignmentStrategy");
  f.write("problem.json", R"({"mapFile": "maps/none.map", "agentFile": "agents.txt", "teamSize": 3, "taskFile": "tasks.txt"})");
  expect_error("none.map", "");
  f.write("problem.json", R"({"mapFile": "maps/small.map", "agentFile": "agents.txt", "teamSize": 3, "taskFile": "tasks.txt"})");
  const std::string agents = f.path("agents.txt"), tasks = f.path("tasks.txt");
  f.write("agents.txt", "3\n0\nx7\n23\n");
  expect_error(agents + ":3:", "x7");
  f.write("agents.txt", "3\n0\n7\n23\n");  // (1,1) is a wall
  expect_error(agents + ":3:", "obstacle");
  f.write("agents.txt", "3\n0\n24\n23\n");
  expect_error(agents + ":3:", "off the map");
  f.write("agents.txt", "3\n0\n11\n");
  expect_error(agents + ":1:", "announces 3");
  f.write("agents.txt", "2\n0\n11\n23\n");
  expect_error(agents + ":4:", "more agents");
  f.write("agents.txt", "3\n0\n11\n0\n");
  expect_error(agents, "same cell");
  f.write("agents.txt", "3\n0\n11\n23\n");
  f.write("tasks.txt", "2\n5\n-3\n");
  expect_error(tasks + ":3:", "-3");
  f.write("tasks.txt", "");
  expect_error(tasks, "empty task file");
  f.write("tasks.txt", "0\n");
  expect_error(tasks, "no tasks");
  f.write("tasks.txt", "5\n5\n18\n2\n12\n23\n");
  EXPECT_EQ(error_of(problem), "(no error)");
}

TEST(LorrIo, TaskListRunsInTheStartKitsOrder) {
  Grid g = Grid::from_rows({"......", "......"});
  const std::vector<Cell> tasks{1, 2, 3, 4, 5};
  TaskListStream rr(g, tasks, 2, TaskListStream::Strategy::RoundRobin);
  // Agent k's j-th task is tasks[(j * 2 + k) % 5]: agent 0 -> 1, 3, 5, 2, ...; agent 1 -> 2, 4, 1.
  EXPECT_EQ(rr.next_goal(0, 0), 1);
  EXPECT_EQ(rr.next_goal(1, 0), 2);
  EXPECT_EQ(rr.next_goal(0, 1), 3);
  EXPECT_EQ(rr.next_goal(0, 3), 5);
  EXPECT_EQ(rr.next_goal(0, 5), 2);
  EXPECT_EQ(rr.next_goal(1, 2), 4);
  EXPECT_EQ(rr.next_goal(1, 4), 1);
  EXPECT_EQ(rr.assigned_ids(0), (std::vector<long>{0, 2, 4, 6}));
  EXPECT_EQ(rr.assigned_ids(1), (std::vector<long>{1, 3, 5}));
  TaskListStream fixed(g, tasks, 2, TaskListStream::Strategy::RoundRobinFixed);
  EXPECT_EQ(fixed.next_goal(1, 0), 2);
  EXPECT_EQ(fixed.next_goal(1, 2), 4);
  EXPECT_EQ(fixed.next_goal(1, 4), 4);  // exhausted: stays
  EXPECT_EQ(fixed.assigned_ids(1), (std::vector<long>{1, 3, -1}));
  TaskListStream greedy(g, tasks, 2, TaskListStream::Strategy::Greedy);
  EXPECT_EQ(greedy.next_goal(1, 0), 1);
  EXPECT_EQ(greedy.next_goal(0, 0), 2);
  EXPECT_EQ(greedy.next_goal(1, 1), 3);
  EXPECT_EQ(greedy.clone_fresh()->next_goal(0, 0), 1);
  // Tasks in another region are skipped.
  Grid split = Grid::from_rows({"..@.."});
  TaskListStream s(split, {3, 1, 4}, 1, TaskListStream::Strategy::RoundRobin);
  EXPECT_EQ(s.next_goal(0, 0), 1);
  EXPECT_THROW(TaskListStream(split, {2}, 1, TaskListStream::Strategy::Greedy), std::invalid_argument);
  EXPECT_THROW(TaskListStream::parse_strategy("fifo"), std::invalid_argument);
}

TEST(LorrIo, MoveLettersFollowPlanViz) {
  // PlanViz's MAPF model: U = row + 1 (down the map as drawn), D = row - 1, R = col + 1, L = col - 1.
  Grid g = Grid::from_rows({"...", "...", "..."});
  const std::vector<std::vector<Cell>> paths{{g.cell(1, 1), g.cell(1, 2), g.cell(1, 1), g.cell(0, 1), g.cell(0, 0),
                                              g.cell(1, 0), g.cell(1, 0)}};
  nlohmann::json j = lorr_output(g, paths, {{g.cell(1, 0)}}, 1);
  EXPECT_EQ(j["actualPaths"][0], "U,D,L,D,R,W");
  EXPECT_EQ(j["start"][0], nlohmann::json({1, 1, "N/A"}));  // [row, col, orientation]
  EXPECT_EQ(j["actionModel"], "MAPF");
  EXPECT_EQ(j["makespan"], 6);
  EXPECT_EQ(j["numTaskFinished"], 1);
  EXPECT_EQ(j["events"][0], nlohmann::json::parse(R"([[0, 0, "assigned"], [0, 5, "finished"]])"));
  EXPECT_EQ(j["tasks"][0], nlohmann::json({0, 0, 1}));  // [id, row, col]
  EXPECT_EQ(read_lorr_paths(g, j, "x"), paths);
  j["actualPaths"][0] = "U,X";
  EXPECT_THROW(read_lorr_paths(g, j, "x"), LorrError);
  j["actualPaths"][0] = "U,U";  // off the map
  EXPECT_THROW(read_lorr_paths(g, j, "x"), LorrError);
}

TEST(LorrIo, OutputReplaysOurOwnPathsExactly) {
  // A LoRR problem on warehouse-10-20-10-2-1 with PIBT: write the run, read the JSON text back,
  // replay the moves: the same cells at every step; the finished events are our goals reached.
  LorrFiles f;
  Grid w = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/warehouse-10-20-10-2-1.map");
  const auto starts = random_starts(w, 60, 3);
  std::string agents = "60\n", tasks = "200\n";
  for (Cell c : starts) agents += std::to_string(c) + "\n";
  const auto task_cells = random_starts(w, 200, 4);
  for (Cell c : task_cells) tasks += std::to_string(c) + "\n";
  f.write("agents.txt", agents);
  f.write("tasks.txt", tasks);
  f.write("problem.json", "{\"mapFile\": \"" + std::string(GDRHCR_SOURCE_DIR) +
                              "/maps/warehouse-10-20-10-2-1.map\", \"agentFile\": \"agents.txt\", \"teamSize\": 60, "
                              "\"taskFile\": \"tasks.txt\", \"numTasksReveal\": 2}");
  LorrProblem p = load_lorr_problem(f.path("problem.json"));
  ASSERT_EQ(p.starts, starts);
  for (auto strategy : {TaskListStream::Strategy::RoundRobin, TaskListStream::Strategy::Greedy}) {
    TaskListStream list(p.grid, p.tasks, p.team_size, strategy);
    RecordingTaskStream rec(list);
    DistTable dist(p.grid);
    Params params;
    auto planner = make_planner("pibt", params, p.grid, p.team_size, 1);
    SimOptions opt;
    opt.steps = 120;
    opt.lookahead = p.num_tasks_reveal;
    opt.record_paths = true;
    const SimResult r = run_simulation(p.grid, dist, rec, *planner, p.starts, opt);
    std::vector<std::vector<long>> ids(p.team_size);
    for (int i = 0; i < p.team_size; ++i) ids[i] = list.assigned_ids(i);
    const std::string text = lorr_output(p.grid, r.paths, rec.goals(), opt.lookahead, ids).dump();
    const nlohmann::json back = nlohmann::json::parse(text);
    EXPECT_EQ(read_lorr_paths(p.grid, back, "round trip"), r.paths);
    EXPECT_GT(r.goals_reached, 20);
    EXPECT_EQ(back["numTaskFinished"].get<long>(), r.goals_reached);
    EXPECT_EQ(back["teamSize"], 60);
    EXPECT_EQ(back["makespan"], 120);
    long finished = 0;
    for (int i = 0; i < p.team_size; ++i)
      for (auto& e : back["events"][i]) {
        const long id = e[0].get<long>(), t = e[1].get<long>();
        if (e[2] == "finished") {
          ++finished;
          // The agent stands on the task's cell at that timestep, and the task is in "tasks".
          EXPECT_EQ(r.paths[i][t], p.tasks[id % p.tasks.size()]);
        }
      }
    EXPECT_EQ(finished, r.goals_reached);
    EXPECT_GE(back["tasks"].size(), size_t(finished));
  }
}


TEST(LorrIo, RotationActionsStopWhoeverFollowsAnAgentThatTurns) {
  Grid g = Grid::from_rows({"......", "......"});
  // A train along row 0 heading east: 0 at (0,0), 1 at (1,0), 2 at (2,0); the front one (2)
  // faces north but wants to go east, so it turns (clockwise from north) and 1 and 0 wait.
  const std::vector<Cell> pos{g.cell(0, 0), g.cell(1, 0), g.cell(2, 0), g.cell(5, 0)};
  const std::vector<Cell> next{g.cell(1, 0), g.cell(2, 0), g.cell(3, 0), g.cell(5, 1)};
  const std::vector<Heading> heading{kEast, kEast, kNorth, kSouth};
  using A = Action;
  const auto act = rotation_actions_for_step(g, pos, heading, next);
  EXPECT_EQ(act, (std::vector<A>{A::kWait, A::kWait, A::kClockwise, A::kForward}));
  // Facing away (west, wants east): a half turn, clockwise first; facing south: counter-clockwise.
  EXPECT_EQ(rotation_actions_for_step(g, {g.cell(5, 0)}, {kWest}, {g.cell(4, 0)})[0], A::kForward);
  EXPECT_EQ(rotation_actions_for_step(g, {g.cell(0, 0)}, {kWest}, {g.cell(1, 0)})[0], A::kClockwise);
  EXPECT_EQ(rotation_actions_for_step(g, {g.cell(0, 0)}, {kSouth}, {g.cell(1, 0)})[0], A::kCounterClockwise);
  // A rotating cycle of four, all facing their next cell, moves as one.
  const std::vector<Cell> cyc{g.cell(0, 0), g.cell(1, 0), g.cell(1, 1), g.cell(0, 1)};
  const std::vector<Cell> cyc_next{g.cell(1, 0), g.cell(1, 1), g.cell(0, 1), g.cell(0, 0)};
  EXPECT_EQ(rotation_actions_for_step(g, cyc, {kEast, kSouth, kWest, kNorth}, cyc_next), std::vector<A>(4, A::kForward));
  // One of them turning stops the whole cycle.
  EXPECT_EQ(rotation_actions_for_step(g, cyc, {kEast, kSouth, kWest, kWest}, cyc_next),
            (std::vector<A>{A::kWait, A::kWait, A::kWait, A::kClockwise}));
  EXPECT_THROW(rotation_actions_for_step(g, {g.cell(0, 0)}, {kEast}, {g.cell(2, 0)}), std::logic_error);
}

TEST(LorrIo, RotationActionsOfAPlannerStayValidStepAfterStep) {
  // PIBT on warehouse-10-20-10-2-1 with 150 agents for 150 steps, its steps executed as MAPF_T
  // actions: every executed step is valid, agents only move along their heading, and they
  // still deliver (turning costs time, it does not stop them).
  Grid w = Grid::load(std::string(GDRHCR_SOURCE_DIR) + "/maps/warehouse-10-20-10-2-1.map");
  DistTable dist(w);
  Params params;
  const int n = 150;
  auto planner = make_planner("pibt", params, w, n, 1);
  RandomNavigationStream tasks(w, 2);
  std::vector<Cell> pos = random_starts(w, n, 5), next(n);
  std::vector<Heading> heading(n);
  for (int i = 0; i < n; ++i) heading[i] = static_cast<Heading>(i % 4);
  std::vector<std::vector<Cell>> goals(n);
  for (int i = 0; i < n; ++i) goals[i] = {tasks.next_goal(i, pos[i])};
  StepValidator validator(w, ActionModel::kRotation);
  long reached = 0, forward = 0;
  for (int t = 0; t < 150; ++t) {
    std::fill(next.begin(), next.end(), kNoCell);
    planner->plan_step(WorldView{w, dist, t, pos, goals}, next);
    const auto act = rotation_actions_for_step(w, pos, heading, next);
    std::vector<Cell> moved = pos;
    std::vector<Heading> turned = heading;
    for (int i = 0; i < n; ++i) {
      const Pose p = apply_action(w, Pose{pos[i], heading[i]}, act[i]);
      moved[i] = p.cell, turned[i] = p.heading;
      ASSERT_TRUE(moved[i] == pos[i] || moved[i] == next[i]) << "agent " << i << " left its planned cell";
      forward += moved[i] != pos[i];
    }
    ASSERT_NO_THROW(validator.require_valid(pos, moved, t, &heading, &turned));
    pos = moved;
    heading = turned;
    for (int i = 0; i < n; ++i)
      if (pos[i] == goals[i][0]) ++reached, goals[i][0] = tasks.next_goal(i, pos[i]);
  }
  EXPECT_GT(forward, 150 * 20);
  EXPECT_GT(reached, 30);
}
