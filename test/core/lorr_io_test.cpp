// LoRR instances in and out: problem files parse, bad ones are rejected naming the file and the
// line or field, the task list runs in the Start-Kit's order, and the output JSON replays our
// own paths exactly (round trip through the JSON text).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <unistd.h>

#include "gdrhcr/lorr_io.hpp"
#include "gdrhcr/mapf_in_rotation.hpp"
#include "gdrhcr/params.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/simulator.hpp"

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
  // Ids count assignments in the order they were made (the Start-Kit's task_id).
  EXPECT_EQ(rr.assigned_ids(0), (std::vector<long>{0, 2, 3, 4}));
  EXPECT_EQ(rr.assigned_ids(1), (std::vector<long>{1, 5, 6}));
  TaskListStream fixed(g, tasks, 2, TaskListStream::Strategy::RoundRobinFixed);
  EXPECT_EQ(fixed.next_goal(1, 0), 2);
  EXPECT_EQ(fixed.next_goal(1, 2), 4);
  EXPECT_EQ(fixed.next_goal(1, 4), 4);  // exhausted: stays
  // Ids agent-major: agent 0 holds tasks 0, 2, 4 (ids 0..2), agent 1 tasks 1, 3 (ids 3, 4).
  EXPECT_EQ(fixed.assigned_ids(1), (std::vector<long>{3, 4, -1}));
  EXPECT_FALSE(fixed.is_errand(1, 4, 4));  // exhausted: its own cell, no errand
  EXPECT_EQ(fixed.next_goal(0, 0), 1);
  EXPECT_EQ(fixed.assigned_ids(0), (std::vector<long>{0}));
  TaskListStream greedy(g, tasks, 2, TaskListStream::Strategy::Greedy);
  EXPECT_EQ(greedy.next_goal(1, 0), 1);
  EXPECT_EQ(greedy.next_goal(0, 0), 2);
  EXPECT_EQ(greedy.next_goal(1, 1), 3);
  EXPECT_EQ(greedy.clone_fresh()->next_goal(0, 0), 1);
  // As in the Start-Kit, a task in another region is assigned all the same, and a task on the
  // agent's own cell (or equal to its previous one) is an errand of length zero.
  Grid split = Grid::from_rows({"..@.."});
  TaskListStream s(split, {3, 1, 1}, 1, TaskListStream::Strategy::RoundRobin);
  EXPECT_EQ(s.next_goal(0, 0), 3);
  EXPECT_TRUE(s.is_errand(0, 3, 0));
  EXPECT_EQ(s.next_goal(0, 3), 1);
  EXPECT_EQ(s.next_goal(0, 1), 1);
  EXPECT_TRUE(s.is_errand(0, 1, 1));
  RandomNavigationStream alone(Grid::from_rows({".@."}), 1);
  EXPECT_FALSE(alone.is_errand(0, 0, 0));  // elsewhere a goal on the agent's own cell is none
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
  EXPECT_EQ(j["makespan"], 5);  // the Start-Kit's: timesteps with a task (finished at t = 5)
  EXPECT_EQ(j["sumOfCost"], 5);
  EXPECT_EQ(j["plannerPaths"], j["actualPaths"]);
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
    std::map<long, Cell> task_cell;  // "tasks": [id, row, col], by id
    for (auto& e : back["tasks"]) task_cell[e[0].get<long>()] = p.grid.cell(e[2].get<int>(), e[1].get<int>());
    long finished = 0;
    for (int i = 0; i < p.team_size; ++i)
      for (auto& e : back["events"][i]) {
        const long id = e[0].get<long>(), t = e[1].get<long>();
        if (e[2] == "finished") {
          ++finished;
          // The agent stands on the task's cell at that timestep, and the task is in "tasks".
          ASSERT_TRUE(task_cell.count(id)) << id;
          EXPECT_EQ(r.paths[i][t], task_cell[id]);
        }
      }
    EXPECT_EQ(finished, r.goals_reached);
    EXPECT_GE(back["tasks"].size(), size_t(finished));
  }
}

namespace {
// One LoRR run of problem `p` with a planner (PIBT by default), in `model` (in rotation with
// mapf-wait by default: a plain mapf planner whose moves are easy to count by hand); the
// recorded goals come back in `goals`.
SimResult run_lorr(const LorrProblem& p, int steps, ActionModel model, std::vector<std::vector<Cell>>* goals = nullptr,
                   const std::string& planner_name = "pibt", TurnPlanning turns = TurnPlanning::kMapfWait) {
  TaskListStream list(p.grid, p.tasks, p.team_size, p.strategy);
  RecordingTaskStream rec(list);
  DistTable dist(p.grid, model);
  Params params;
  const PlannerParams values = PlannerParams::resolve(planner_name, params, MapFacts(p.grid, p.team_size));
  auto planner = make_planner_in(values, p.grid, p.team_size, 1, model, turns);
  SimOptions opt;
  opt.steps = steps;
  opt.lookahead = p.num_tasks_reveal;
  opt.record_paths = true;
  opt.action_model = model;
  SimResult r = run_simulation(p.grid, dist, rec, *planner, p.starts, opt);
  if (goals) *goals = rec.goals();
  return r;
}
}  // namespace

TEST(LorrIo, ErrandsOfZeroLengthCountAsInTheStartKit) {
  // One agent in a corridor of 3 starting at its west end, tasks [0, 0, 2, 2] (linear ids):
  // finished by standing on them after a step, as the Start-Kit's BaseSystem::move checks.
  // mapf: t = 1 (task on the start cell), 2 (equal to the previous one), 4, 5, then cell 0 at 7.
  LorrFiles f;
  f.write("maps/c.map", "type octile\nheight 1\nwidth 3\nmap\n...\n");
  f.write("a.txt", "1\n0\n");
  f.write("t.txt", "4\n0\n0\n2\n2\n");
  f.write("c.json", R"({"mapFile": "maps/c.map", "agentFile": "a.txt", "teamSize": 1, "taskFile": "t.txt"})");
  const LorrProblem p = load_lorr_problem(f.path("c.json"));
  SimResult r = run_lorr(p, 7, ActionModel::kMapf);
  EXPECT_EQ(r.goals_reached, 5);
  EXPECT_DOUBLE_EQ(r.free_flow_throughput, 5.0 / 7);
  // Rotation, facing east: the same until t = 5, then a half turn (t = 6, 7) and two steps west.
  EXPECT_EQ(run_lorr(p, 8, ActionModel::kRotation).goals_reached, 4);
  std::vector<std::vector<Cell>> goals;
  r = run_lorr(p, 9, ActionModel::kRotation, &goals);
  EXPECT_EQ(r.goals_reached, 5);
  const nlohmann::json out = lorr_output(p.grid, r.paths, goals, 1, {{0, 1, 2, 3, 4, 5}}, &r.headings);
  EXPECT_EQ(out["numTaskFinished"], 5);
  EXPECT_EQ(out["actualPaths"][0], "W,W,F,F,W,R,R,F,F");
  EXPECT_EQ(out["events"][0], nlohmann::json::parse(R"([[0,0,"assigned"],[0,1,"finished"],[1,1,"assigned"],
      [1,2,"finished"],[2,2,"assigned"],[2,4,"finished"],[3,4,"assigned"],[3,5,"finished"],[4,5,"assigned"],
      [4,9,"finished"],[5,9,"assigned"]])"));
}

TEST(LorrIo, UnreachableTasksAreAssignedAndHoldTheirAgent) {
  // "..@..": agent 0 on the left gets task 0 on the right, which it can never reach, and keeps
  // it (the Start-Kit assigns it and checks only the front task); agent 1 on the right finishes
  // one task per step (tasks[1] = 4, tasks[3] = 3, alternating). Every planner copes (RHCR,
  // knowing one goal ahead, waits on a reached goal until its next replanning, every alpha steps).
  LorrFiles f;
  f.write("maps/s.map", "type octile\nheight 1\nwidth 5\nmap\n..@..\n");
  f.write("a.txt", "2\n0\n3\n");
  f.write("t.txt", "4\n4\n4\n0\n3\n");
  f.write("s.json", R"({"mapFile": "maps/s.map", "agentFile": "a.txt", "teamSize": 2, "taskFile": "t.txt"})");
  const LorrProblem p = load_lorr_problem(f.path("s.json"));
  for (const std::string name : {"pibt", "rhcr", "gd-rhcr"}) {
    std::vector<std::vector<Cell>> goals;
    const SimResult r = run_lorr(p, 10, ActionModel::kMapf, &goals, name);
    EXPECT_EQ(goals[0], std::vector<Cell>{4}) << name;  // never replaced
    EXPECT_EQ(goals[1].size(), size_t(r.goals_reached) + 1) << name;
    EXPECT_EQ(r.goals_reached, name == "rhcr" ? 2 : 10) << name;
  }
}

TEST(LorrIo, OnlyAtAndTBlockAsInTheStartKit) {
  // The Start-Kit's Grid blocks '@' and 'T' only; MovingAI's 'O' and 'W' (blocked by Grid::load)
  // are free in a LoRR map, so an agent may start on them.
  LorrFiles f;
  f.write("maps/o.map", "type octile\nheight 2\nwidth 4\nmap\n.OW@\nTSE.\n");
  const Grid ours = Grid::load(f.path("maps/o.map"));
  const Grid lorr = load_lorr_map(f.path("maps/o.map"));
  EXPECT_FALSE(ours.is_free(ours.cell(1, 0)));
  EXPECT_FALSE(ours.is_free(ours.cell(2, 0)));
  for (int x : {0, 1, 2}) EXPECT_TRUE(lorr.is_free(lorr.cell(x, 0))) << x;
  EXPECT_FALSE(lorr.is_free(lorr.cell(3, 0)));
  EXPECT_FALSE(lorr.is_free(lorr.cell(0, 1)));
  for (int x : {1, 2, 3}) EXPECT_TRUE(lorr.is_free(lorr.cell(x, 1))) << x;
  f.write("a.txt", "1\n2\n");  // (2,0), a 'W'
  f.write("t.txt", "1\n1\n");
  f.write("o.json", R"({"mapFile": "maps/o.map", "agentFile": "a.txt", "teamSize": 1, "taskFile": "t.txt"})");
  EXPECT_EQ(load_lorr_problem(f.path("o.json")).starts, std::vector<Cell>{2});
  // The Start-Kit's other header, "rows,cols"; bad headers and short rows are named.
  f.write("maps/k.map", "2,3\n.@.\nT..\n");
  EXPECT_EQ(load_lorr_map(f.path("maps/k.map")).free_cells(), (std::vector<Cell>{0, 2, 4, 5}));
  auto error = [&](const std::string& text) {
    f.write("maps/bad.map", text);
    try {
      load_lorr_map(f.path("maps/bad.map"));
    } catch (const LorrError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(error("type octile\nheight 2\nwidth 4\nmap\n....\n..\n").find("bad.map:6: row 1 has 2 cells"), std::string::npos);
  EXPECT_NE(error("type octile\nheight x\n").find("bad.map:2: height must be a positive integer"), std::string::npos);
  EXPECT_NE(error("2,3\n...\n").find("the map has 1 rows"), std::string::npos);
  EXPECT_NE(error("hello\n").find("bad.map:1: expected a MovingAI header"), std::string::npos);
  EXPECT_NE(error("1,2\n@T\n").find("bad.map"), std::string::npos);  // no free cell
}

TEST(LorrIo, RotationOutputIsTheStartKitsAndReplaysExactly) {
  // A rotation run written as the Start-Kit writes its output: MAPF_T, F/R/C/W, start facing east,
  // plannerPaths; read back (cells and headings) it replays the run exactly.
  LorrFiles f;
  const LorrProblem p = load_lorr_problem(f.path("problem.json"));
  std::vector<std::vector<Cell>> goals;
  const SimResult r = run_lorr(p, 40, ActionModel::kRotation, &goals, "gd-rhcr", kLorrTurnPlanning);
  const nlohmann::json out = nlohmann::json::parse(lorr_output(p.grid, r.paths, goals, 2, {}, &r.headings).dump());
  EXPECT_EQ(out["actionModel"], "MAPF_T");
  EXPECT_EQ(out["start"][1], nlohmann::json({1, 5, "E"}));
  EXPECT_EQ(out["plannerPaths"], out["actualPaths"]);
  std::set<char> letters;
  for (auto& s : out["actualPaths"])
    for (char c : s.get<std::string>()) letters.insert(c);
  EXPECT_EQ(letters, (std::set<char>{',', 'F', 'R', 'C', 'W'}));
  std::vector<std::vector<Heading>> headings;
  EXPECT_EQ(read_lorr_paths(p.grid, out, "rotation", &headings), r.paths);
  EXPECT_EQ(headings, r.headings);
  EXPECT_EQ(out["numTaskFinished"].get<long>(), r.goals_reached);
  nlohmann::json bad = out;
  bad["actualPaths"][0] = "F,L";
  EXPECT_THROW(read_lorr_paths(p.grid, bad, "x"), LorrError);  // L is no MAPF_T letter
  bad["start"][0][2] = "X";
  EXPECT_THROW(read_lorr_paths(p.grid, bad, "x"), LorrError);
}
