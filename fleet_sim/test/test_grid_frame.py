#!/usr/bin/env python3
"""Unit tests of the grid/frame conversion and the simulator's move resolution (no master needed)."""
import unittest

from fleet_sim.grid_frame import GridFrame, resolve_moves


class GridFrameTest(unittest.TestCase):
    def test_round_trip_and_flip(self):
        # 3 wide, 2 high; occupancy row 0 is the bottom = grid row 1.
        g = GridFrame(3, 2, 0.5, 1.0, 2.0, [0, 100, 0, 0, 0, 100])
        self.assertTrue(g.is_free(0, 1))
        self.assertFalse(g.is_free(1, 1))
        self.assertFalse(g.is_free(2, 0))
        self.assertEqual(g.world(0, 1), (1.25, 2.25))
        self.assertEqual(g.cell(*g.world(2, 0)), (2, 0))
        self.assertEqual(len(g.free_cells()), 4)


class ResolveMovesTest(unittest.TestCase):
    def test_chain_behind_frozen_robot_waits(self):
        cells = [(0, 0), (1, 0), (2, 0)]
        targets = [(1, 0), (2, 0), (3, 0)]
        moves, blocked = resolve_moves(cells, targets, [False, False, True])
        self.assertEqual(moves, set())
        self.assertEqual(blocked, {0, 1})

    def test_train_moves_together(self):
        cells = [(0, 0), (1, 0), (2, 0)]
        targets = [(1, 0), (2, 0), (3, 0)]
        moves, blocked = resolve_moves(cells, targets, [False] * 3)
        self.assertEqual(moves, {0, 1, 2})
        self.assertEqual(blocked, set())

    def test_swap_refused(self):
        moves, blocked = resolve_moves([(0, 0), (1, 0)], [(1, 0), (0, 0)], [False, False])
        self.assertEqual(moves, set())


if __name__ == "__main__":
    import rosunit

    class AllTests(GridFrameTest, ResolveMovesTest):
        pass

    rosunit.unitrun("fleet_sim", "grid_frame", AllTests)
