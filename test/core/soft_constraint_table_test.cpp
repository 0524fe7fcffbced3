// SoftConstraintTable: vertex and swap counts over time, agents parked after their path ends,
// clearing and refilling.
#include <gtest/gtest.h>

#include "gdrhcr/soft_constraint_table.hpp"

using namespace gdrhcr;

TEST(SoftConstraintTable, CountsVerticesEdgesAndParking) {
  Grid g = Grid::from_rows({"....", "...."});
  SoftConstraintTable soft(g);
  EXPECT_TRUE(soft.empty());
  const Cell a = g.cell(0, 0), b = g.cell(1, 0), c = g.cell(2, 0);
  soft.add_path({a, b, b, c});   // moves a->b at 0, waits, b->c at 2, then parks at c
  soft.add_path({c, b});         // c->b at 0, parks at b
  EXPECT_FALSE(soft.empty());
  EXPECT_EQ(soft.num_paths(), 2);
  EXPECT_EQ(soft.vertex_count(a, 0), 1);
  EXPECT_EQ(soft.vertex_count(a, 1), 0);
  EXPECT_EQ(soft.vertex_count(b, 1), 2);   // both
  EXPECT_EQ(soft.vertex_count(b, 7), 1);   // the second one parked there
  EXPECT_EQ(soft.vertex_count(c, 3), 1);
  EXPECT_EQ(soft.vertex_count(c, 100), 1);
  EXPECT_EQ(soft.vertex_count(c, 1), 0);
  // A move b -> a at 0 swaps with the first agent (a -> b at 0).
  EXPECT_EQ(soft.edge_count(b, a, 0), 1);
  EXPECT_EQ(soft.edge_count(a, b, 0), 0);
  EXPECT_EQ(soft.edge_count(b, c, 0), 1);  // the second one moves c -> b at 0
  EXPECT_EQ(soft.edge_count(c, b, 2), 1);
  EXPECT_EQ(soft.edge_count(b, b, 1), 0);  // waiting is never a swap
  int counts[6] = {0, 0, 0, 0, 0, 0};
  soft.add_vertex_counts(b, 5, counts);
  EXPECT_EQ(counts[0], 0);
  EXPECT_EQ(counts[1], 2);
  EXPECT_EQ(counts[2], 2);
  EXPECT_EQ(counts[3], 1);
  EXPECT_EQ(counts[5], 1);
  EXPECT_TRUE(soft.touches(b));
  EXPECT_FALSE(soft.touches(g.cell(3, 1)));

  soft.clear();
  EXPECT_TRUE(soft.empty());
  EXPECT_EQ(soft.vertex_count(b, 1), 0);
  EXPECT_FALSE(soft.touches(b));
  soft.add_path({g.cell(3, 1)});
  EXPECT_EQ(soft.vertex_count(g.cell(3, 1), 0), 1);
  EXPECT_EQ(soft.vertex_count(g.cell(3, 1), 50), 1);
}
