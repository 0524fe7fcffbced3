// The step validator catches injected vertex, edge, obstacle and jump violations.
#include <gtest/gtest.h>

#include "gdrhcr/validator.hpp"

using namespace gdrhcr;

class ValidatorTest : public ::testing::Test {
 protected:
  Grid g = Grid::from_rows({"....", ".@..", "...."});
  StepValidator v{g};
  Cell c(int x, int y) { return g.cell(x, y); }
};

TEST_F(ValidatorTest, AcceptsMovesWaitsAndFollowing) {
  // Agent 0 follows agent 1 into the cell it leaves; agent 2 waits.
  EXPECT_FALSE(v.check({c(0, 0), c(1, 0), c(3, 2)}, {c(1, 0), c(2, 0), c(3, 2)}));
  // A rotation around a 2x2 block of free cells is legal (no swap).
  EXPECT_FALSE(v.check({c(2, 1), c(3, 1), c(3, 2), c(2, 2)}, {c(3, 1), c(3, 2), c(2, 2), c(2, 1)}));
}

TEST_F(ValidatorTest, CatchesVertexCollision) {
  auto r = v.check({c(0, 0), c(2, 0)}, {c(1, 0), c(1, 0)});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Vertex);
  EXPECT_EQ(r->agent_a, 0);
  EXPECT_EQ(r->agent_b, 1);
}

TEST_F(ValidatorTest, CatchesVertexCollisionWithWaitingAgent) {
  auto r = v.check({c(0, 0), c(1, 0)}, {c(1, 0), c(1, 0)});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Vertex);
}

TEST_F(ValidatorTest, CatchesEdgeCollision) {
  auto r = v.check({c(0, 0), c(1, 0), c(3, 2)}, {c(1, 0), c(0, 0), c(3, 2)});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Edge);
  EXPECT_TRUE((r->agent_a == 0 && r->agent_b == 1) || (r->agent_a == 1 && r->agent_b == 0));
}

TEST_F(ValidatorTest, CatchesObstacleAndJump) {
  auto r = v.check({c(1, 0)}, {c(1, 1)});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Obstacle);
  r = v.check({c(0, 0)}, {c(2, 0)});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Jump);
  r = v.check({c(0, 0)}, {c(1, 0) + 100});
  ASSERT_TRUE(r);
  EXPECT_EQ(r->kind, StepViolation::Kind::Obstacle);
}

TEST_F(ValidatorTest, RequireValidThrowsWithDescription) {
  try {
    v.require_valid({c(0, 0), c(1, 0)}, {c(1, 0), c(0, 0)}, 7);
    FAIL() << "swap not reported";
  } catch (const CollisionError& e) {
    std::string m = e.what();
    EXPECT_NE(m.find("edge collision"), std::string::npos) << m;
    EXPECT_NE(m.find("step 7"), std::string::npos) << m;
  }
}

TEST_F(ValidatorTest, StampsDoNotLeakBetweenSteps) {
  EXPECT_FALSE(v.check({c(0, 0)}, {c(1, 0)}));
  // Cell (1,0) was occupied in the previous check; a different agent may use it now.
  EXPECT_FALSE(v.check({c(2, 0)}, {c(1, 0)}));
}
