// The rotation action model (issue 23, LoRR's MAPF_T): headings and actions exactly as the LoRR
// Start-Kit v1.1.5 defines them, the validator's checks of the model's moves, distance rows that
// count turns, and the simulator carrying headings and validating every step.
#include <gtest/gtest.h>

#include <deque>

#include "list_stream.hpp"

#include "gdrhcr/action_model.hpp"
#include "gdrhcr/dist_table.hpp"
#include "gdrhcr/planner.hpp"
#include "gdrhcr/simulator.hpp"
#include "gdrhcr/validator.hpp"

using namespace gdrhcr;
using gdrhcr::test_support::ListStream;

namespace {
std::string repo(const std::string& rel) { return std::string(GDRHCR_SOURCE_DIR) + "/" + rel; }
}  // namespace

TEST(ActionModel, ParsesAndNamesBothModelsAndNamesABadValue) {
  EXPECT_EQ(parse_action_model("mapf"), ActionModel::kMapf);
  EXPECT_EQ(parse_action_model("rotation"), ActionModel::kRotation);
  EXPECT_STREQ(action_model_name(ActionModel::kMapf), "mapf");
  EXPECT_STREQ(action_model_name(ActionModel::kRotation), "rotation");
  try {
    parse_action_model("MAPF_T");
    FAIL() << "bad value accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'MAPF_T'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("rotation"), std::string::npos) << e.what();
  }
}

// Start-Kit: moves[] = {+1, +cols, -1, -cols} for orientation 0..3; CR = (o + 1) % 4.
TEST(ActionModel, HeadingsMoveAsTheStartKitsOrientation) {
  Grid g = Grid::from_rows({".....", ".....", "....."});
  const Cell c = g.cell(2, 1);
  EXPECT_EQ(forward_cell(g, c, kEast), c + 1);
  EXPECT_EQ(forward_cell(g, c, kSouth), c + g.width());
  EXPECT_EQ(forward_cell(g, c, kWest), c - 1);
  EXPECT_EQ(forward_cell(g, c, kNorth), c - g.width());
  EXPECT_EQ(rotate_cw(kEast), kSouth);
  EXPECT_EQ(rotate_cw(kNorth), kEast);
  EXPECT_EQ(rotate_ccw(kEast), kNorth);
  EXPECT_EQ(rotate_ccw(kSouth), kEast);
  EXPECT_EQ(turn_steps(kEast, kEast), 0);
  EXPECT_EQ(turn_steps(kEast, kNorth), 1);
  EXPECT_EQ(turn_steps(kEast, kSouth), 1);
  EXPECT_EQ(turn_steps(kEast, kWest), 2);
  EXPECT_EQ(turn_steps(kNorth, kSouth), 2);
  for (Heading h = 0; h < kNumHeadings; ++h) EXPECT_EQ(heading_of_move(g, c, forward_cell(g, c, h)), h);
  EXPECT_EQ(heading_of_move(g, c, c), kNoHeading);
  EXPECT_EQ(heading_of_move(g, c, g.cell(4, 1)), kNoHeading);
  EXPECT_STREQ(heading_name(kSouth), "S");
}

TEST(ActionModel, ForwardOffTheMapOrIntoAnObstacleHasNoCell) {
  Grid g = Grid::from_rows({"..@", "..."});
  EXPECT_EQ(forward_cell(g, g.cell(1, 0), kEast), kNoCell);   // obstacle
  EXPECT_EQ(forward_cell(g, g.cell(2, 1), kEast), kNoCell);   // east edge (not the next row's first cell)
  EXPECT_EQ(forward_cell(g, g.cell(0, 0), kNorth), kNoCell);  // top edge
  EXPECT_EQ(forward_cell(g, g.cell(0, 1), kWest), kNoCell);
  EXPECT_EQ(apply_action(g, {g.cell(1, 0), kEast}, Action::kForward).cell, kNoCell);
}

TEST(ActionModel, ActionBetweenStatesUsesTheStartKitsLetters) {
  Grid g = Grid::from_rows({"...", "...", "..."});
  const Cell c = g.cell(1, 1);
  auto letter = [&](Pose a, Pose b) {
    auto act = action_between(g, a, b);
    return act ? action_letter(*act) : '-';
  };
  EXPECT_EQ(letter({c, kEast}, {c + 1, kEast}), 'F');
  EXPECT_EQ(letter({c, kEast}, {c, kSouth}), 'R');
  EXPECT_EQ(letter({c, kEast}, {c, kNorth}), 'C');
  EXPECT_EQ(letter({c, kWest}, {c, kWest}), 'W');
  EXPECT_EQ(letter({c, kEast}, {c - 1, kEast}), '-');   // backwards
  EXPECT_EQ(letter({c, kEast}, {c + 3, kSouth}), '-');  // a move and a turn at once
  EXPECT_EQ(letter({c, kEast}, {c + 1, kSouth}), '-');  // forward with a turn
  EXPECT_EQ(letter({c, kEast}, {c, kWest}), '-');       // half turn in one step
  EXPECT_EQ(letter({c, kEast}, {c + 2, kEast}), '-');   // jump
  for (Action a : {Action::kForward, Action::kClockwise, Action::kCounterClockwise, Action::kWait})
    for (Heading h = 0; h < kNumHeadings; ++h)
      EXPECT_EQ(action_between(g, {c, h}, apply_action(g, {c, h}, a)), a);
}

class RotationValidatorTest : public ::testing::Test {
 protected:
  Grid g = Grid::from_rows({"....", ".@..", "...."});
  StepValidator v{g, ActionModel::kRotation};
  Cell c(int x, int y) { return g.cell(x, y); }
};

TEST_F(RotationValidatorTest, AcceptsOneActionPerAgent) {
  const std::vector<Heading> h0{kEast, kSouth, kWest, kNorth}, h1{kEast, kWest, kSouth, kNorth};
  // 0: (0,0) E forward to (1,0); 1: (3,0) S -> W by R; 2: (3,2) W -> S by C; 3: (0,2) waits.
  EXPECT_FALSE(v.check({c(0, 0), c(3, 0), c(3, 2), c(0, 2)}, {c(1, 0), c(3, 0), c(3, 2), c(0, 2)}, &h0, &h1));
}

TEST_F(RotationValidatorTest, RejectsAMoveTheHeadingDoesNotFace) {
  const std::vector<Heading> h{kNorth};
  auto r = v.check({c(0, 0)}, {c(1, 0)}, &h, &h);  // a sideways step: fine in mapf, not here
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Action);
  const std::string m = r->describe(g, 4);
  EXPECT_NE(m.find("agent 0"), std::string::npos) << m;
  EXPECT_NE(m.find("facing N"), std::string::npos) << m;
  EXPECT_NE(m.find("rotation model"), std::string::npos) << m;
  StepValidator mapf(g);
  EXPECT_FALSE(mapf.check({c(0, 0)}, {c(1, 0)}));
}

TEST_F(RotationValidatorTest, RejectsAHalfTurnAndATurnWithAMove) {
  const std::vector<Heading> e{kEast}, w{kWest}, s{kSouth};
  auto r = v.check({c(0, 0)}, {c(0, 0)}, &e, &w);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Action);
  r = v.check({c(0, 0)}, {c(1, 0)}, &e, &s);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Action);
}

TEST_F(RotationValidatorTest, StillCatchesVertexAndEdgeCollisionsAndMissingHeadings) {
  const std::vector<Heading> ew{kEast, kWest};
  auto r = v.check({c(0, 0), c(1, 0)}, {c(1, 0), c(0, 0)}, &ew, &ew);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Edge);
  r = v.check({c(0, 0), c(2, 0)}, {c(1, 0), c(1, 0)}, &ew, &ew);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Vertex);
  r = v.check({c(0, 0), c(2, 0)}, {c(0, 0), c(2, 0)});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Heading);
  const std::vector<Heading> bad{kEast, 7};
  r = v.check({c(0, 0), c(2, 0)}, {c(0, 0), c(2, 0)}, &ew, &bad);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Heading);
  EXPECT_EQ(r->agent_a, 1);
}

namespace {
// Distances from every state to `goal` by a forward BFS from each state, with apply_action alone
// (independent of the table's reverse BFS).
int forward_bfs(const Grid& g, Pose from, Cell goal) {
  std::vector<int> d(size_t(g.num_cells()) * 4, -1);
  std::deque<Pose> q{from};
  d[from.cell * 4 + from.heading] = 0;
  while (!q.empty()) {
    const Pose p = q.front();
    q.pop_front();
    if (p.cell == goal) return d[p.cell * 4 + p.heading];
    for (Action a : {Action::kForward, Action::kClockwise, Action::kCounterClockwise}) {
      const Pose n = apply_action(g, p, a);
      if (n.cell == kNoCell || d[n.cell * 4 + n.heading] >= 0) continue;
      d[n.cell * 4 + n.heading] = d[p.cell * 4 + p.heading] + 1;
      q.push_back(n);
    }
  }
  return kUnreachable;
}
}  // namespace

TEST(RotationDistTable, RowsCountTurnsExactly) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  DistTable rot(g, ActionModel::kRotation), flat(g);
  EXPECT_EQ(rot.action_model(), ActionModel::kRotation);
  const auto& free = g.free_cells();
  for (int k = 0; k < 3; ++k) {
    const Cell goal = free[(k * 271 + 13) % free.size()];
    auto row = rot.row(goal);
    for (int s = 0; s < 25; ++s) {
      const Cell c = free[(s * 97 + k * 31) % free.size()];
      int least = kUnreachable;
      for (Heading h = 0; h < kNumHeadings; ++h) {
        const int d = row->at(c, h);
        EXPECT_EQ(d, forward_bfs(g, {c, h}, goal)) << g.describe(c) << " heading " << int(h);
        EXPECT_GE(d, flat.get(goal, c));  // turns only add
        least = std::min(least, d);
      }
      EXPECT_EQ((*row)[c], least);
    }
    for (Heading h = 0; h < kNumHeadings; ++h) EXPECT_EQ(row->at(goal, h), 0);
  }
  EXPECT_EQ(flat.row(free[0])->at(free[5], kWest), flat.get(free[0], free[5]));  // mapf ignores headings
}

TEST(RotationDistTable, FacingAwayCostsTwoTurnsAndBlockedCellsAreAvoided) {
  const Grid g = Grid::from_rows({".....", "....."});
  DistTable dist(g, ActionModel::kRotation);
  const Cell goal = g.cell(4, 0);
  EXPECT_EQ(dist.get(goal, g.cell(0, 0), kEast), 4);
  EXPECT_EQ(dist.get(goal, g.cell(0, 0), kWest), 6);
  EXPECT_EQ(dist.get(goal, g.cell(0, 0), kNorth), 5);
  EXPECT_EQ(dist.get(goal, g.cell(0, 0)), 4);
  // (2,0) blocked: around it through the bottom row, 6 moves and 2 turns from (0,0) facing south.
  DistTable around(g, {g.cell(2, 0)}, ActionModel::kRotation);
  EXPECT_EQ(around.get(goal, g.cell(0, 0), kSouth), 1 + 1 + 4 + 1 + 1);
}

namespace {
// One agent (or several far apart) following its rotation row greedily: forward first.
class GreedyTurner : public Planner {
 public:
  std::string name() const override { return "greedy-turner"; }
  StepReport plan_step(const WorldView& w, std::vector<Cell>& next) override {
    check_action_model(name(), ActionModel::kRotation, w);
    for (int i = 0; i < w.num_agents(); ++i) {
      auto row = w.dist.row(w.goals[i][0]);
      Pose best = w.pose(i);
      for (Action a : {Action::kForward, Action::kClockwise, Action::kCounterClockwise}) {
        const Pose q = apply_action(w.grid, w.pose(i), a);
        if (q.cell != kNoCell && row->at(q.cell, q.heading) < row->at(best.cell, best.heading)) best = q;
      }
      next[i] = best.cell;
      (*w.next_headings)[i] = best.heading;
    }
    return {true, 0};
  }
  nlohmann::json params() const override { return nlohmann::json::object(); }
};

// Rotation: turns or moves like GreedyTurner on odd timesteps, and waits on even ones.
class Dawdler : public GreedyTurner {
 public:
  StepReport plan_step(const WorldView& w, std::vector<Cell>& next) override {
    if (w.timestep % 2 == 1) return GreedyTurner::plan_step(w, next);
    for (int i = 0; i < w.num_agents(); ++i) next[i] = w.positions[i], (*w.next_headings)[i] = (*w.headings)[i];
    return {true, 0};
  }
};

// Moves sideways, which the rotation model forbids.
class Sidestepper : public GreedyTurner {
 public:
  StepReport plan_step(const WorldView& w, std::vector<Cell>& next) override {
    next[0] = forward_cell(w.grid, w.positions[0], kSouth);
    (*w.next_headings)[0] = (*w.headings)[0];
    return {};
  }
};
}  // namespace

TEST(RotationSimulation, CarriesHeadingsCountsTurnsAndRecordsTheModel) {
  const Grid g = Grid::from_rows({".....", "....."});
  DistTable dist(g, ActionModel::kRotation);
  ListStream tasks({{g.cell(4, 0), g.cell(0, 0)}});
  GreedyTurner planner;
  SimOptions opt;
  opt.steps = 14;
  opt.record_paths = true;
  opt.action_model = ActionModel::kRotation;
  const SimResult r = run_simulation(g, dist, tasks, planner, {g.cell(0, 0)}, opt);
  // East 4 steps, two turns and 4 back: goals at t = 4 and t = 10; a third leg is under way.
  EXPECT_EQ(r.goals_reached, 2);
  EXPECT_EQ(r.paths[0][4], g.cell(4, 0));
  EXPECT_EQ(r.paths[0][10], g.cell(0, 0));
  ASSERT_EQ(r.headings.size(), 1u);
  EXPECT_EQ(r.headings[0][0], kEast);
  EXPECT_EQ(r.headings[0][10], kWest);
  EXPECT_EQ(r.action_model, ActionModel::kRotation);
  EXPECT_EQ(r.to_json()["action_model"], "rotation");
  // Free flow with turns: legs of 4, 6, 6 steps -> 2 goals in 14 steps (without turns: 3).
  EXPECT_DOUBLE_EQ(r.free_flow_throughput, 2.0 / 14);
  DistTable flat(g);
  EXPECT_DOUBLE_EQ(free_flow_throughput(g, flat, tasks, {g.cell(0, 0)}, 14), 3.0 / 14);
}

static void expect_steps(const ErrandSteps& got, long errands, long steps, long forward, long turns, long waits) {
  EXPECT_EQ(got.errands, errands);
  EXPECT_EQ(got.steps(), steps);
  EXPECT_EQ(got.forward, forward);
  EXPECT_EQ(got.turns, turns);
  EXPECT_EQ(got.waits, waits);
}

TEST(RotationSimulation, ErrandStepsSplitIntoForwardMovesTurnsAndWaitsAgainstFreeFlow) {
  const Grid g = Grid::from_rows({".....", "....."});
  DistTable dist(g, ActionModel::kRotation);
  ListStream tasks({{g.cell(4, 0), g.cell(0, 0)}});
  SimOptions opt;
  opt.steps = 14;
  opt.action_model = ActionModel::kRotation;
  GreedyTurner greedy;  // legs of 4 forward, then 2 turns and 4 forward: as in free flow
  const SimResult r = run_simulation(g, dist, tasks, greedy, {g.cell(0, 0)}, opt);
  expect_steps(r.errand_steps, 2, 10, 8, 2, 0);
  expect_steps(r.free_flow_errand_steps, 2, 10, 8, 2, 0);
  EXPECT_EQ(r.to_json()["errand_steps"]["reached"]["turns_per_errand"], 1.0);
  // Waiting every other step: the first leg takes 8 steps, 4 of them waits; the second leg is
  // not done in 14 steps and does not count.
  Dawdler dawdler;
  ListStream fresh({{g.cell(4, 0), g.cell(0, 0)}});
  const SimResult d = run_simulation(g, dist, fresh, dawdler, {g.cell(0, 0)}, opt);
  expect_steps(d.errand_steps, 1, 8, 4, 0, 4);
  EXPECT_EQ(d.to_json()["errand_steps"]["reached"]["waits_per_errand"], 4.0);
  EXPECT_EQ(d.free_flow_errand_steps.steps(), r.free_flow_errand_steps.steps());  // the same errands
}

TEST(RotationSimulation, StartHeadingsAreUsedAndCheckedAgainstTheFleet) {
  const Grid g = Grid::from_rows({".....", "....."});
  DistTable dist(g, ActionModel::kRotation);
  ListStream tasks(std::vector<std::vector<Cell>>{{g.cell(4, 0)}});
  GreedyTurner planner;
  SimOptions opt;
  opt.steps = 5;
  opt.action_model = ActionModel::kRotation;
  opt.start_headings = {kWest};
  EXPECT_EQ(run_simulation(g, dist, tasks, planner, {g.cell(0, 0)}, opt).goals_reached, 0);  // 6 steps needed
  opt.start_headings = {kEast, kEast};
  EXPECT_THROW(run_simulation(g, dist, tasks, planner, {g.cell(0, 0)}, opt), std::invalid_argument);
}

TEST(RotationSimulation, ASidewaysMoveIsACollisionErrorNamingTheRotationModel) {
  const Grid g = Grid::from_rows({".....", "....."});
  DistTable dist(g, ActionModel::kRotation);
  ListStream tasks(std::vector<std::vector<Cell>>{{g.cell(4, 0)}});
  Sidestepper planner;
  SimOptions opt;
  opt.steps = 3;
  opt.action_model = ActionModel::kRotation;
  try {
    run_simulation(g, dist, tasks, planner, {g.cell(0, 0)}, opt);
    FAIL() << "sideways move accepted";
  } catch (const CollisionError& e) {
    EXPECT_NE(std::string(e.what()).find("rotation model"), std::string::npos) << e.what();
  }
}

TEST(RotationSimulation, ADistanceTableOfAnotherModelIsRejected) {
  const Grid g = Grid::from_rows({".....", "....."});
  DistTable flat(g);
  ListStream tasks(std::vector<std::vector<Cell>>{{g.cell(4, 0)}});
  GreedyTurner planner;
  SimOptions opt;
  opt.action_model = ActionModel::kRotation;
  EXPECT_THROW(run_simulation(g, flat, tasks, planner, {g.cell(0, 0)}, opt), std::invalid_argument);
}

TEST(RotationPlanners, APlannerThatDoesNotPlanWithTurnsIsRejectedByName) {
  const Grid g = Grid::load(repo("maps/random-32-32-20.map"));
  for (const std::string& name : planner_names()) {
    Params none;
    if (planner_supports(name, ActionModel::kRotation)) {
      EXPECT_NO_THROW(make_planner(name, none, g, 4, 1, ActionModel::kRotation)) << name;
      continue;
    }
    try {
      make_planner(name, none, g, 4, 1, ActionModel::kRotation);
      FAIL() << name << " accepted the rotation model";
    } catch (const ParamError& e) {
      EXPECT_NE(std::string(e.what()).find("'" + name + "'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("rotation"), std::string::npos) << e.what();
    }
  }
}

TEST(RotationPlanners, APlannerBuiltForMapfRefusesARotationWorld) {
  const Grid g = Grid::from_rows({".....", "....."});
  DistTable dist(g, ActionModel::kRotation);
  Params none;
  auto planner = make_planner("pibt", none, g, 1, 1);
  ListStream tasks(std::vector<std::vector<Cell>>{{g.cell(4, 0)}});
  SimOptions opt;
  opt.steps = 2;
  opt.action_model = ActionModel::kRotation;
  EXPECT_THROW(run_simulation(g, dist, tasks, *planner, {g.cell(0, 0)}, opt), std::invalid_argument);
}
