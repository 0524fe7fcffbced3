#!/usr/bin/env python3
"""Unit tests of the grid/frame conversion, the simulator's move resolution and its fault
schedules and slip rule (no master needed)."""
import math
import unittest

from fleet_sim.faults import FaultSchedule, RandomDelays, slip_target
from fleet_sim.grid_frame import GridFrame, resolve_moves, tick_entry_taken


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


class TickEntryTest(unittest.TestCase):
    def test_an_array_older_than_the_update_is_dropped_and_a_restarted_manager_is_followed(self):
        self.assertTrue(tick_entry_taken(-1, 1))      # no update yet
        self.assertFalse(tick_entry_taken(800, 800))  # tick 800's array after an update of tick 800
        self.assertFalse(tick_entry_taken(800, 799))
        self.assertTrue(tick_entry_taken(800, 801))
        # The planner was killed at tick 800 and respawned: its ticks count from 1 again, and a
        # robot that dropped them would ignore it for 800 ticks (the 20-minute soak at fc1d387
        # delivered nothing after its first restart).
        self.assertTrue(tick_entry_taken(800, 1))
        self.assertTrue(tick_entry_taken(800, 797))


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


class RandomDelaysTest(unittest.TestCase):
    class R(object):
        def __init__(self, moving=False):
            self.delay_until, self.moving, self.duration = 0.0, moving, 0.3

    def test_every_robot_delayed_one_to_d_ticks_when_p_is_one(self):
        robots = [self.R(moving=(i % 2 == 0)) for i in range(200)]
        d = RandomDelays(1.0, 4, seed=3)
        self.assertEqual(d.tick(10.0, 0.5, robots), 200)
        lengths = set(round((r.delay_until - 10.0) / 0.5) for r in robots)
        self.assertEqual(lengths, {1, 2, 3, 4})
        for r in robots:  # a moving robot arrives that much later
            self.assertAlmostEqual(r.duration, 0.3 + (r.delay_until - 10.0) if r.moving else 0.3)
        self.assertEqual(d.tick(10.25, 0.5, robots), 0)  # nobody starts a second delay while delayed

    def test_rate_and_seed(self):
        def run(seed):
            robots = [self.R() for _ in range(100)]
            d = RandomDelays(0.01, 20, seed=seed)
            return sum(d.tick(t * 0.5, 0.5, robots) for t in range(1000)), [r.delay_until for r in robots]
        a, b = run(1), run(1)
        self.assertEqual(a, b)
        # 100 robots x 1000 ticks, p 0.01, each delay idles a robot ~10.5 ticks on average:
        # about 100000 / (100 + 10.5) = 905 delays.
        self.assertTrue(700 < a[0] < 1100, a[0])
        self.assertEqual(RandomDelays(0.0, 20, 1).tick(0.0, 0.5, [self.R()]), 0)
        with self.assertRaises(ValueError):
            RandomDelays(0.1, 0, 1)


if __name__ == "__main__":
    import rosunit

    class AllTests(GridFrameTest, ResolveMovesTest, SlipTest, FaultScheduleTest, RandomDelaysTest):
        pass

    rosunit.unitrun("fleet_sim", "grid_frame", AllTests)
