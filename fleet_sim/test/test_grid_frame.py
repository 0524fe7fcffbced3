#!/usr/bin/env python3
"""Unit tests of the grid/frame conversion, the simulator's move resolution and its fault
schedules and slip rule (no master needed)."""
import math
import unittest

from fleet_sim.faults import FaultSchedule, slip_target
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

    def test_cell_a_moving_robot_enters_is_held(self):
        # Robot 1 is still moving from (2, 0) into (1, 0): robot 0 may not enter (1, 0), and
        # robot 2 behind robot 0 waits too.
        cells = [(0, 0), (2, 0), (-1, 0)]
        targets = [(1, 0), (2, 0), (0, 0)]
        moves, blocked = resolve_moves(cells, targets, [False, True, False], reserved=[(1, 0)])
        self.assertEqual(moves, set())
        self.assertEqual(blocked, {0, 2})


class SlipTest(unittest.TestCase):
    def test_perpendicular_first_then_reverse_then_stay(self):
        free = lambda x, y: 0 <= x < 3 and 0 <= y < 3
        # Commanded +x from the centre: +y is tried first, then -y, then -x.
        self.assertEqual(slip_target((1, 1), (2, 1), free, set()), (1, 2))
        self.assertEqual(slip_target((1, 1), (2, 1), free, {(1, 2)}), (1, 0))
        self.assertEqual(slip_target((1, 1), (2, 1), free, {(1, 2), (1, 0)}), (0, 1))
        self.assertIsNone(slip_target((1, 1), (2, 1), free, {(1, 2), (1, 0), (0, 1)}))
        # Never the commanded cell, never off the map.
        self.assertIsNone(slip_target((0, 0), (1, 0), free, {(0, 1)}))


class FaultScheduleTest(unittest.TestCase):
    def test_one_shot_timed(self):
        f = FaultSchedule("stop", 2, 5.0, 3.0, 10)
        self.assertEqual(f.update(None), [])
        self.assertEqual(f.update(4.9), [])
        self.assertFalse(f.active(2, 4.9))
        opened = f.update(5.2)
        self.assertEqual(len(opened), 1)
        self.assertEqual(opened[0].start, 5.0)  # at the due time, not at the update
        self.assertTrue(f.active(2, 5.2))
        self.assertFalse(f.active(3, 5.2))
        self.assertTrue(f.active(2, 7.9))
        f.update(8.0)
        self.assertFalse(f.active(2, 8.0))
        self.assertEqual(f.update(100.0), [])
        self.assertEqual(f.fired, 1)

    def test_for_good_and_disabled(self):
        f = FaultSchedule("stop", 0, 1.0, -1.0, 4)
        f.update(1.0)
        self.assertTrue(f.active(0, 1e9))
        self.assertEqual(f.last.until, math.inf)
        g = FaultSchedule("stop", -1, 1.0, -1.0, 4)
        self.assertEqual(g.update(50.0), [])
        self.assertFalse(g.active(0, 50.0))

    def test_waits_for_condition(self):
        task = {1: -1}
        f = FaultSchedule("stop", 1, 5.0, 2.0, 4,
                          ready=lambda rid: task[rid] if task[rid] >= 0 else None)
        self.assertEqual(f.update(6.0), [])
        self.assertFalse(f.active(1, 6.0))
        task[1] = 42
        ep = f.update(6.5)[0]
        self.assertEqual((ep.robot, ep.start, ep.until, ep.info), (1, 6.5, 8.5, 42))

    def test_periodic_moves_between_robots_and_skips_missed(self):
        ready = {0: True, 3: None, 6: True}
        f = FaultSchedule("silent", 0, 10.0, 5.0, 8, period=20.0, stride=3,
                          ready=lambda rid: ready.get(rid))
        self.assertEqual([e.robot for e in f.update(10.0)], [0])
        self.assertEqual(f.update(31.0), [])  # robot 3 is not ready
        self.assertEqual([e.robot for e in f.update(50.0)], [6])  # robot 3's turn was missed
        self.assertEqual(f.missed, 1)
        self.assertTrue(f.active(6, 54.0))
        self.assertFalse(f.active(0, 54.0))

    def test_slip_counts(self):
        f = FaultSchedule("slip", 4, 2.0, -1.0, 8, count=2)
        f.update(1.0)
        self.assertIsNone(f.pending_slip(4, 1.0))
        f.update(2.0)
        ep = f.pending_slip(4, 2.5)
        ep.left -= 1
        self.assertIs(f.pending_slip(4, 3.0), ep)
        ep.left -= 1
        f.update(3.5)
        self.assertIsNone(f.pending_slip(4, 3.5))


if __name__ == "__main__":
    import rosunit

    class AllTests(GridFrameTest, ResolveMovesTest, SlipTest, FaultScheduleTest):
        pass

    rosunit.unitrun("fleet_sim", "grid_frame", AllTests)
