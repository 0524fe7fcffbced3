// Bad and odd input (issue 7): map files that lie, are empty, binary or huge; maps whose free
// cells fall apart into regions, and the task streams on them (goals always reachable, MAPD
// sets that cannot reach each other rejected naming a cell).
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "gdrhcr/grid.hpp"
#include "gdrhcr/guided_pibt.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/task_stream.hpp"

using namespace gdrhcr;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }

// The MapError message of parsing `text` with Grid::parse (format detection), or "" on success.
std::string parse_error(const std::string& text) {
  std::istringstream in(text);
  try {
    Grid::parse(in, "t.map");
  } catch (const MapError& e) {
    return e.what();
  }
  return "";
}

Grid parse_ok(const std::string& text) {
  std::istringstream in(text);
  return Grid::parse(in, "t.map");
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// Left region 3x3 (cells x 0..2), a wall, right region 1x3 (x 4), and an isolated cell (6,1).
//   ...@.@@
//   ...@.@.
//   ...@.@@
Grid three_regions() { return Grid::from_rows({"...@.@@", "...@.@.", "...@.@@"}, "three"); }
}  // namespace

TEST(RobustMap, HugeHeaderIsRejectedBeforeAllocating) {
  const std::string e = parse_error("type octile\nheight 100000\nwidth 100000\nmap\n...\n");
  EXPECT_TRUE(has(e, "t.map:4")) << e;
  EXPECT_TRUE(has(e, "100000 x 100000 = 10000000000 cells is larger than the limit")) << e;
  const std::string k = parse_error("999999999,999999999\n1\n1\n1\n");
  EXPECT_TRUE(has(k, "t.map:1")) << k;
  EXPECT_TRUE(has(k, "larger than the limit")) << k;
  // Ten digits cannot even be a size.
  EXPECT_TRUE(has(parse_error("type octile\nheight 1234567890\nwidth 1\nmap\n"), "height must be a positive integer"));
  // A header just under the limit with no rows is a plain truncation error.
  EXPECT_TRUE(has(parse_error("type octile\nheight 4096\nwidth 4096\nmap\n"), "expected 4096 rows, found 0"));
}

TEST(RobustMap, EmptyBinaryAndHeaderOnlyFiles) {
  EXPECT_TRUE(has(parse_error(""), "t.map: empty map file"));
  EXPECT_TRUE(has(parse_error("\n  \n\t\n"), "empty map file"));
  const std::string bin = parse_error(std::string("\x7f" "ELF\x02\x01\x00\xff\xfe", 9) + "\n");
  EXPECT_TRUE(has(bin, "unrecognised map format")) << bin;
  EXPECT_TRUE(has(bin, "\\x7fELF\\x02\\x01\\x00\\xff\\xfe")) << bin;  // escaped, not raw bytes
  // Garbage with a comma is taken for a kiva header, and rejected as one.
  const std::string kbin = parse_error(std::string("\x01\x02,\x03\n", 5));
  EXPECT_TRUE(has(kbin, "expected 'rows,cols'")) << kbin;
  EXPECT_TRUE(has(kbin, "\\x01\\x02,\\x03")) << kbin;
  // Very long garbage is quoted only in part.
  EXPECT_LT(parse_error(std::string(100000, '?') + "\n").size(), 300u);
  EXPECT_TRUE(has(parse_error("type octile\nheight 2\nwidth 2\nmap\n"), "truncated map: expected 2 rows, found 0"));
  EXPECT_TRUE(has(parse_error("type octile\nheight 2\nwidth 2\n"), "missing 'map' line"));
  EXPECT_TRUE(has(parse_error("33,46\n480\n"), "t.map:3: truncated kiva header"));
  EXPECT_TRUE(has(parse_error("2,2\n0\n0\n0\n"), "t.map:5: truncated map"));
  // Grid::load on an empty file says so too.
  const std::string path = testing::TempDir() + "/empty.map";
  std::ofstream(path).close();
  try {
    Grid::load(path);
    FAIL() << "accepted an empty file";
  } catch (const MapError& e) {
    EXPECT_TRUE(has(e.what(), "empty.map: empty map file")) << e.what();
  }
}

TEST(RobustMap, TabsDuplicatesAndMissingFinalNewline) {
  // Tabs separate header words and trail rows like spaces do; inside a row they are an error.
  Grid g = parse_ok("type\toctile\nheight\t1\nwidth 2\t\nmap\n..\t\n");
  EXPECT_EQ(g.width(), 2);
  const std::string tab = parse_error("type octile\nheight 1\nwidth 2\nmap\n.\t\n");
  EXPECT_TRUE(has(tab, "t.map:5")) << tab;  // stripped to width 1
  EXPECT_TRUE(has(parse_error("type octile\nheight 1\nwidth 3\nmap\n.\t.\n"), "unknown map symbol '\\x09' at column 1"));
  EXPECT_TRUE(has(parse_error("type octile\nheight 1\nwidth 2\nmap\n.\x01\n"), "unknown map symbol '\\x01'"));
  // No newline after the last row: fine in both formats.
  EXPECT_EQ(parse_ok("type octile\nheight 1\nwidth 2\nmap\n..").free_cells().size(), 2u);
  EXPECT_EQ(parse_ok("1,2\n0\n0\n0\ner").homes().size(), 1u);
  // Repeated or extended header lines are mistakes, not silently overridden.
  EXPECT_TRUE(has(parse_error("type octile\nheight 1\nheight 2\nwidth 2\nmap\n..\n"), "t.map:3: duplicate 'height'"));
  EXPECT_TRUE(has(parse_error("type octile\ntype octile\nheight 1\nwidth 2\nmap\n..\n"), "duplicate 'type'"));
  EXPECT_TRUE(has(parse_error("type octile\nheight 1\nwidth 2\nmap ..\n..\n"), "unexpected text after 'map'"));
}

TEST(RobustMap, KivaHeaderLies) {
  // rows,cols must match the rows exactly.
  EXPECT_TRUE(has(parse_error("3,2\n0\n0\n0\n..\n..\n"), "t.map:7: truncated map: expected 3 rows, found 2"));
  EXPECT_TRUE(has(parse_error("1,2\n0\n0\n0\n..\n..\n"), "t.map:6: unexpected text after the last map row"));
  EXPECT_TRUE(has(parse_error("2,3\n0\n0\n0\n..\n..\n"), "t.map:5: row 0 has 2 cells, expected width 3"));
  EXPECT_TRUE(has(parse_error("2,1\n0\n0\n0\n..\n..\n"), "row 0 has 2 cells, expected width 1"));
  // The endpoint/agent/time numbers are ignored by RHCR's loader and tolerated here, even when
  // they disagree with the rows; they must still be numbers.
  Grid g = parse_ok("2,3\n99\n7\n5000\ne.r\n...\n");
  EXPECT_EQ(g.endpoints().size(), 1u);
  EXPECT_EQ(g.homes().size(), 1u);
  EXPECT_TRUE(has(parse_error("2,3\n-1\n7\n5000\ne.r\n...\n"), "t.map:2: expected a number"));
}

TEST(RobustMap, ComponentsOfADisconnectedMap) {
  Grid g = three_regions();
  ASSERT_EQ(g.count_components(), 3);
  EXPECT_EQ(g.component(g.cell(0, 0)), 0);
  EXPECT_EQ(g.component(g.cell(4, 0)), 1);
  EXPECT_EQ(g.component(g.cell(6, 1)), 2);
  EXPECT_EQ(g.component(g.cell(3, 0)), -1);  // obstacle
  EXPECT_EQ(g.component(-5), -1);
  EXPECT_EQ(g.component_cells(0).size(), 9u);
  EXPECT_EQ(g.component_cells(1), (std::vector<Cell>{g.cell(4, 0), g.cell(4, 1), g.cell(4, 2)}));
  EXPECT_EQ(g.component_cells(2), (std::vector<Cell>{g.cell(6, 1)}));
  Grid w = Grid::load(repo("maps/warehouse-10-20-10-2-1.map"));
  EXPECT_EQ(w.component_cells(0), w.free_cells());
}

TEST(RobustTasks, RandomGoalsStayInTheAgentsRegion) {
  Grid g = three_regions();
  RandomNavigationStream s(g, 11);
  for (Cell start : {g.cell(1, 1), g.cell(4, 2)}) {
    const int agent = g.x_of(start);
    Cell cur = start;
    std::set<Cell> seen;
    for (int k = 0; k < 200; ++k) {
      const Cell next = s.next_goal(agent, cur);
      ASSERT_EQ(g.component(next), g.component(start)) << g.describe(next);
      ASSERT_NE(next, cur);
      seen.insert(next);
      cur = next;
    }
    EXPECT_EQ(seen.size(), g.component_cells(g.component(start)).size());  // all of it, fairly
  }
  // Alone in a one-cell region: the only reachable goal is the cell itself.
  EXPECT_EQ(s.next_goal(6, g.cell(6, 1)), g.cell(6, 1));
  EXPECT_THROW(s.next_goal(0, g.cell(3, 0)), std::invalid_argument);  // standing on a wall
}

TEST(RobustTasks, RandomSequenceDependsOnSeedAgentAndStartOnly) {
  Grid g = three_regions();
  RandomNavigationStream a(g, 4), b(g, 4);
  std::vector<Cell> seq_a, seq_b;
  Cell ca = g.cell(4, 0), cb = g.cell(4, 0);
  for (int k = 0; k < 20; ++k) seq_a.push_back(ca = a.next_goal(3, ca));
  for (int k = 0; k < 20; ++k) {
    b.next_goal(0, g.cell(0, 0));  // other agents, other regions, interleaved
    seq_b.push_back(cb = b.next_goal(3, cb));
    b.next_goal(9, g.cell(6, 1));
  }
  EXPECT_EQ(seq_a, seq_b);
  // On a connected map the draw is the plain uniform draw over all free cells, so results of
  // earlier runs on the shipped maps are unchanged.
  Grid r = Grid::load(repo("maps/random-32-32-20.map"));
  RandomNavigationStream s(r, 9);
  std::mt19937_64 rng(mix_seed(9 ^ 0x52414e44ULL, 2));
  Cell cur = r.free_cells()[0];
  for (int k = 0; k < 50; ++k) {
    Cell expect;
    do {
      expect = r.free_cells()[std::uniform_int_distribution<size_t>(0, r.free_cells().size() - 1)(rng)];
    } while (expect == cur);
    ASSERT_EQ(s.next_goal(2, cur), expect) << k;
    cur = expect;
  }
}

TEST(RobustTasks, MapdSetsThatCannotReachEachOtherAreRejected) {
  Grid g = three_regions();
  const Cell left = g.cell(0, 0), left2 = g.cell(2, 2), right = g.cell(4, 1);
  auto error = [&](std::vector<Cell> p, std::vector<Cell> d) -> std::string {
    try {
      PickupDeliveryStream s(g, p, d, 1);
    } catch (const std::invalid_argument& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error({left}, {left2}), "");
  std::string e = error({left, right}, {left2});
  EXPECT_TRUE(has(e, "MAPD pickup cell (4,1) cannot reach any delivery cell")) << e;
  EXPECT_TRUE(has(e, "region of 3 free cells")) << e;
  e = error({left}, {left2, g.cell(6, 1)});
  EXPECT_TRUE(has(e, "MAPD delivery cell (6,1) cannot reach any pickup cell")) << e;
  EXPECT_TRUE(has(error({left}, {g.cell(3, 1)}), "delivery cell (3,1) is not a free cell"));
  EXPECT_THROW(check_mapd_cells(g, {}, {left}), std::invalid_argument);
}

TEST(RobustTasks, MapdGoalsStayInRegionAndStartsWithoutPickupsFail) {
  Grid g = three_regions();
  // Pickups and deliveries in both big regions; nothing in the isolated cell.
  const std::vector<Cell> p = {g.cell(0, 0), g.cell(4, 0)}, d = {g.cell(2, 2), g.cell(1, 2), g.cell(4, 2)};
  PickupDeliveryStream s(g, p, d, 5);
  for (Cell start : {g.cell(1, 1), g.cell(4, 1)}) {
    const int agent = g.x_of(start);
    Cell cur = start;
    for (int k = 0; k < 20; ++k) {
      cur = s.next_goal(agent, cur);
      ASSERT_EQ(g.component(cur), g.component(start));
      const auto& set = k % 2 == 0 ? p : d;
      ASSERT_TRUE(std::count(set.begin(), set.end(), cur)) << k;
    }
  }
  try {
    s.next_goal(7, g.cell(6, 1));
    FAIL() << "gave a task to an agent that cannot reach any pickup";
  } catch (const std::invalid_argument& e) {
    EXPECT_TRUE(has(e.what(), "agent 7 at (6,1) cannot reach any pickup cell")) << e.what();
  }
  // Through the simulator: the error comes before the first step.
  DistTable dist(g);
  PibtPlanner planner(g, 2, 1);
  PickupDeliveryStream fresh(g, p, d, 5);
  EXPECT_THROW(run_simulation(g, dist, fresh, planner, {g.cell(0, 1), g.cell(6, 1)}, SimOptions{}),
               std::invalid_argument);
}

TEST(RobustTasks, DefaultMapdRuleDropsUnreachableCells) {
  // A sealed room (inside the ring of '@') whose cells are "beside an obstacle" but cannot reach
  // the delivery columns x=0 and x=8.
  Grid g = Grid::from_rows({".........", ".@@@@@.@.", ".@...@...", ".@@@@@.@.", "........."});
  ASSERT_EQ(g.count_components(), 2);
  MapdCells cells = default_mapd_cells(g);
  for (Cell c : cells.pickups) EXPECT_NE(g.component(c), g.component(g.cell(3, 2))) << g.describe(c);
  EXPECT_TRUE(has(cells.rule, "3 cells dropped")) << cells.rule;
  EXPECT_NO_THROW(check_mapd_cells(g, cells.pickups, cells.deliveries));
}

TEST(RobustTasks, AgentAloneInOneCellScoresNothing) {
  Grid g = three_regions();
  DistTable dist(g);
  RandomNavigationStream tasks(g, 3);
  PibtPlanner planner(g, 2, 1);
  SimOptions opt;
  opt.steps = 40;
  const SimResult r = run_simulation(g, dist, tasks, planner, {g.cell(6, 1), g.cell(4, 0)}, opt);
  // Agent 0 cannot move; only agent 1 (in the 3-cell column) reaches goals, at most one every
  // step and at least one every 2 steps (goals are at most 2 moves away and it is alone).
  EXPECT_GE(r.goals_reached, 20);
  EXPECT_LE(r.goals_reached, 40);
  EXPECT_LE(r.free_flow_throughput, 1.0);
  RandomNavigationStream alone(g, 3);
  PibtPlanner one(g, 1, 1);
  EXPECT_EQ(run_simulation(g, dist, alone, one, {g.cell(6, 1)}, opt).goals_reached, 0);
  EXPECT_EQ(free_flow_throughput(g, dist, alone, {g.cell(6, 1)}, 40), 0.0);
}

TEST(RobustTasks, CellListStreamErrors) {
  Grid g = three_regions();
  auto error = [&](const std::string& text) -> std::string {
    std::istringstream in(text);
    try {
      parse_cell_list(g, in, "c.txt");
    } catch (const MapError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error("0 0\n\n  # comment\n4,2\n"), "");
  EXPECT_TRUE(has(error(""), "c.txt: no cells listed"));
  EXPECT_TRUE(has(error("0 0\n99999999999999999999 1\n"), "c.txt:2: expected 'x y'"));
  EXPECT_TRUE(has(error("-1 0\n"), "c.txt:1: cell (-1,0) is off the map (7 x 3)"));
  EXPECT_TRUE(has(error("4294967296 0\n"), "cell (4294967296,0) is off the map"));
  EXPECT_TRUE(has(error("0 0 0\n"), "expected 'x y'"));
  EXPECT_TRUE(has(error(std::string("0\x00 1\n", 5)), "'0\\x00 1'"));
}
