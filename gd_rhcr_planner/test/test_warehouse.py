#!/usr/bin/env python3
"""Headless integration test: planner node + fleet_sim + task generator (see *.test).

Checks, over one run: tasks are delivered with status transitions queued -> assigned -> picked ->
delivered; no two robots ever share a cell, swap cells or jump (every pair of consecutive
RobotStateArray messages); step commands arrive at the tick rate; a late subscriber gets the
latched map, MAPD cells and markers; bad tasks (obstacle, off-map, unknown cells) are rejected
with a reason while the node keeps running; an unknown robot id is ignored; service and action
round trips. With ~faults set (faults_integration.test: a stalled, a slipping, a stopped and a
silent robot, and a planner missing its deadline) the same safety checks hold, the stopped robot
never moves, its task is requeued and delivered by another robot, the silent robot is counted
offline and comes back, deliveries go on after the faults, and PIBT fallback ticks are counted.
"""
import threading
import time
import unittest

import actionlib
import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import OccupancyGrid
from visualization_msgs.msg import MarkerArray

from gd_rhcr_msgs.msg import (DeliveryAction, DeliveryGoal, MapdCells, PlannerStats, RobotState,
                              RobotStateArray, StepCommand, StepCommandArray, Task, TaskStatus)
from gd_rhcr_msgs.srv import CancelTask, ListTasks, SubmitTask

PKG = "gd_rhcr_planner"


class Recorder(object):
    def __init__(self):
        self.lock = threading.Lock()
        self.prev_cells = None
        self.state_msgs = 0
        self.violations = []
        self.offline_moves = []
        self.step_times = []
        self.step_ticks = []
        self.step_sizes = []
        self.step_ids = None  # robots named in every step command so far (None: no command yet)
        self.status = {}  # task id -> list of states
        self.events = {}  # task id -> list of (state, robot, reason, time)
        self.reasons = {}
        self.offline_history = []  # (time, offline robots) whenever the count changes
        self.sim_diag = {}
        self.planner_diag = {}
        self.stats = None
        self.robot0_cmds = 0
        self.offline_cell = {}
        rospy.Subscriber("robot_states", RobotStateArray, self.on_states, queue_size=100)
        rospy.Subscriber("step_commands", StepCommandArray, self.on_steps, queue_size=100)
        rospy.Subscriber("task_status", TaskStatus, self.on_status, queue_size=1000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag, queue_size=100)
        rospy.Subscriber("planner_stats", PlannerStats, self.on_stats, queue_size=10)
        rospy.Subscriber("robot_0/step_command", StepCommand, self.on_robot0, queue_size=10)

    def on_states(self, msg):
        cells = {r.id: (r.x, r.y) for r in msg.robots}
        with self.lock:
            self.state_msgs += 1
            if len(set(cells.values())) != len(cells):
                self.violations.append("shared cell in %s" % sorted(cells.items()))
            prev = self.prev_cells
            if prev is not None:
                where = {c: i for i, c in prev.items()}
                for i, c in cells.items():
                    p = prev.get(i)
                    if p is None:
                        continue
                    if abs(p[0] - c[0]) + abs(p[1] - c[1]) > 1:
                        self.violations.append("robot %d jumped %s -> %s" % (i, p, c))
                    j = where.get(c)
                    if j is not None and j != i and c != p and cells.get(j) == p:
                        self.violations.append("robots %d and %d swapped %s <-> %s" % (i, j, p, c))
            for r in msg.robots:
                # A robot that goes offline mid-move still finishes that move; from its first
                # report at rest it must never move again.
                if r.mode == RobotState.MODE_OFFLINE and not r.moving:
                    first = self.offline_cell.setdefault(r.id, (r.x, r.y))
                    if first != (r.x, r.y):
                        self.offline_moves.append((r.id, first, (r.x, r.y)))
            self.prev_cells = cells

    def on_steps(self, msg):
        with self.lock:
            self.step_times.append(time.time())
            self.step_ticks.append(msg.tick)
            self.step_sizes.append(len(msg.commands))
            ids = set(c.robot_id for c in msg.commands)
            self.step_ids = ids if self.step_ids is None else self.step_ids & ids

    def on_status(self, msg):
        with self.lock:
            self.status.setdefault(msg.task_id, []).append(msg.state)
            self.events.setdefault(msg.task_id, []).append((msg.state, msg.robot_id, msg.reason, time.time()))
            self.reasons[msg.task_id] = msg.reason

    def on_diag(self, msg):
        with self.lock:
            for s in msg.status:
                d = dict((kv.key, kv.value) for kv in s.values)
                if "blocked moves" in d:
                    self.sim_diag = d
                elif "tick rate measured (Hz)" in d:
                    self.planner_diag = d

    def on_stats(self, msg):
        with self.lock:
            self.stats = msg
            if not self.offline_history or self.offline_history[-1][1] != msg.offline_robots:
                self.offline_history.append((time.time(), msg.offline_robots))

    def on_robot0(self, _msg):
        with self.lock:
            self.robot0_cmds += 1

    def delivered(self, min_id=0):
        with self.lock:
            return [t for t, s in self.status.items() if t >= min_id and TaskStatus.DELIVERED in s]


def wait_for(predicate, timeout, step=0.1):
    deadline = time.time() + timeout
    while time.time() < deadline and not rospy.is_shutdown():
        if predicate():
            return True
        time.sleep(step)
    return predicate()


class WarehouseTest(unittest.TestCase):
    rec = None

    @classmethod
    def setUpClass(cls):
        cls.rec = Recorder()
        cls.num_robots = rospy.get_param("~num_robots")
        cls.tick_rate = rospy.get_param("~tick_rate")
        cls.faults = rospy.get_param("~faults", False)
        cls.deliveries_wanted = rospy.get_param("~deliveries", 5)
        cls.run_time = rospy.get_param("~run_time", 60.0)
        cls.t_start = time.time()
        if not wait_for(lambda: len(cls.rec.step_ticks) >= 3, 30):
            raise AssertionError("no step commands within 30 s")

    def test_1_late_subscriber_gets_latched_map_and_markers(self):
        og = rospy.wait_for_message("map", OccupancyGrid, timeout=5)
        self.assertEqual(og.header.frame_id, "map")
        self.assertGreater(og.info.width * og.info.height, 0)
        self.assertIn(0, og.data)
        self.assertIn(100, og.data)
        cells = rospy.wait_for_message("mapd_cells", MapdCells, timeout=5)
        self.assertGreater(len(cells.pickup_x), 0)
        self.assertGreater(len(cells.delivery_x), 0)
        markers = rospy.wait_for_message("fleet_markers", MarkerArray, timeout=5)
        robots = [m for m in markers.markers if m.ns == "robots"]
        self.assertEqual(len(robots), 1)
        self.assertEqual(len(robots[0].points), 3 * self.num_robots)  # a triangle per robot
        self.assertEqual(robots[0].header.frame_id, "map")

    def test_2_step_commands_at_tick_rate(self):
        self.assertTrue(wait_for(lambda: len(self.rec.step_times) >= 5 * self.tick_rate + 1, 15))
        with self.rec.lock:
            times = list(self.rec.step_times[-int(5 * self.tick_rate):])
            ticks = list(self.rec.step_ticks)
            missing = set(range(self.num_robots)) - self.rec.step_ids
            sizes = set(self.rec.step_sizes)
        period = (times[-1] - times[0]) / (len(times) - 1)
        self.assertAlmostEqual(period, 1.0 / self.tick_rate, delta=0.15 / self.tick_rate)
        # Every robot gets a command every tick, but for a robot caught slipping (moving into a
        # cell it was not commanded: told nothing until it stops); with faults, robot slip_robot.
        self.assertEqual(missing - {rospy.get_param("~slip_robot", -1)}, set())
        self.assertEqual(max(sizes), self.num_robots)
        self.assertEqual(ticks, sorted(ticks))
        self.assertGreater(self.rec.robot0_cmds, 0, "per-robot topic robot_0/step_command is silent")
        self.assertTrue(wait_for(lambda: bool(self.rec.planner_diag), 5), "no planner diagnostics")
        self.assertGreater(float(self.rec.planner_diag["tick rate measured (Hz)"]), 0.8 * self.tick_rate)

    def test_3_bad_input_is_rejected_and_node_keeps_running(self):
        rospy.wait_for_service("submit_task", timeout=5)
        submit = rospy.ServiceProxy("submit_task", SubmitTask)
        # (0, 0) is the wall corner of every shipped map; (10000, 5) is off any map.
        r = submit(Task(pickup_x=0, pickup_y=0, delivery_x=1, delivery_y=1))
        self.assertFalse(r.accepted)
        self.assertIn("obstacle", r.reason)
        r = submit(Task(pickup_x=1, pickup_y=1, delivery_x=10000, delivery_y=5))
        self.assertFalse(r.accepted)
        self.assertIn("off the map", r.reason)
        r = submit(Task(pickup_x=-3, pickup_y=1, delivery_x=1, delivery_y=1))
        self.assertFalse(r.accepted)
        self.assertIn("off the map", r.reason)
        # Over the topic: a FAILED status with the reason.
        pub = rospy.Publisher("tasks", Task, queue_size=10)
        wait_for(lambda: pub.get_num_connections() > 0, 5)
        pub.publish(Task(id=900001, pickup_x=0, pickup_y=0, delivery_x=1, delivery_y=1))
        self.assertTrue(wait_for(lambda: 900001 in self.rec.status, 5), "no status for the bad task")
        self.assertEqual(self.rec.status[900001], [TaskStatus.FAILED])
        self.assertIn("obstacle", self.rec.reasons[900001])
        # An unknown robot id in a state message is ignored.
        spub = rospy.Publisher("robot_states", RobotStateArray, queue_size=10)
        wait_for(lambda: spub.get_num_connections() > 0, 5)
        bogus = RobotStateArray()
        bogus.robots.append(RobotState(id=self.num_robots + 50, x=1, y=1))
        spub.publish(bogus)
        n = len(self.rec.step_ticks)
        self.assertTrue(wait_for(lambda: len(self.rec.step_ticks) >= n + 3, 5), "planner stopped ticking")
        r = submit(Task(pickup_x=1, pickup_y=1, delivery_x=1, delivery_y=2))
        self.assertTrue(r.accepted, r.reason)

    def test_4_service_round_trip(self):
        submit = rospy.ServiceProxy("submit_task", SubmitTask)
        cancel = rospy.ServiceProxy("cancel_task", CancelTask)
        listing = rospy.ServiceProxy("list_tasks", ListTasks)
        r = submit(Task(pickup_x=2, pickup_y=1, delivery_x=3, delivery_y=1, priority=-100))
        self.assertTrue(r.accepted, r.reason)
        ids = [t.id for t in listing(False).tasks]
        self.assertIn(r.task_id, ids)
        c = cancel(r.task_id)
        self.assertTrue(c.success, c.reason)
        c = cancel(r.task_id)
        self.assertFalse(c.success)
        self.assertIn("already", c.reason)
        self.assertFalse(cancel(987654321).success)
        res = listing(True)
        st = dict((s.task_id, s.state) for s in res.statuses)
        self.assertEqual(st[r.task_id], TaskStatus.CANCELLED)
        self.assertNotIn(r.task_id, [t.id for t in listing(False).tasks])

    def test_5_action_round_trip(self):
        client = actionlib.SimpleActionClient("delivery", DeliveryAction)
        self.assertTrue(client.wait_for_server(rospy.Duration(5)))
        feedback = []
        goal = DeliveryGoal(pickup_x=4, pickup_y=1, delivery_x=1, delivery_y=4, priority=100)
        client.send_goal(goal, feedback_cb=lambda fb: feedback.append(fb))
        self.assertTrue(client.wait_for_result(rospy.Duration(self.run_time)), "delivery action timed out")
        result = client.get_result()
        # Also under faults: a task whose robot goes offline is requeued, never dropped.
        self.assertEqual(client.get_state(), actionlib.GoalStatus.SUCCEEDED, result.reason)
        self.assertEqual(result.final_state, TaskStatus.DELIVERED)
        self.assertTrue(any(fb.state == TaskStatus.PICKED for fb in feedback), feedback)
        self.assertTrue(all(fb.distance_left >= 0 for fb in feedback))
        bad = actionlib.SimpleActionClient("delivery", DeliveryAction)
        bad.wait_for_server(rospy.Duration(5))
        bad.send_goal(DeliveryGoal(pickup_x=0, pickup_y=0, delivery_x=1, delivery_y=1))
        self.assertTrue(bad.wait_for_result(rospy.Duration(5)))
        self.assertEqual(bad.get_state(), actionlib.GoalStatus.REJECTED)
        self.assertIn("obstacle", bad.get_result().reason)

    def test_6_tasks_delivered_without_collisions(self):
        wanted = self.deliveries_wanted
        deadline = self.t_start + self.run_time
        ok = wait_for(lambda: len(self.rec.delivered(min_id=1000000)) >= wanted, max(1.0, deadline - time.time()))
        self.assertTrue(ok, "only %d generated tasks delivered" % len(self.rec.delivered(min_id=1000000)))
        with self.rec.lock:
            self.assertEqual(self.rec.violations, [])
            self.assertGreater(self.rec.state_msgs, 50)
            seqs = [self.rec.status[t] for t in self.rec.status if TaskStatus.DELIVERED in self.rec.status[t]]
        for s in seqs:
            picked = s.index(TaskStatus.PICKED)
            self.assertLess(s.index(TaskStatus.ASSIGNED), picked, s)
            self.assertLess(picked, s.index(TaskStatus.DELIVERED), s)
            self.assertEqual(s[-1], TaskStatus.DELIVERED, s)
        self.assertTrue(wait_for(lambda: bool(self.rec.sim_diag), 5))
        if not self.faults:
            # Everybody followed the plan: the simulator's safety stop never had to act.
            self.assertEqual(self.rec.sim_diag["blocked moves"], "0")
            self.assertEqual(self.rec.sim_diag["invalid commands"], "0")
        else:
            self.assertEqual(self.rec.offline_moves, [])
            self.assertIn(0, self.rec.offline_cell, "the stopped robot never reported OFFLINE")
        self.assertIsNotNone(self.rec.stats)
        self.assertEqual(self.rec.stats.num_robots, self.num_robots)

    def test_7_faults_tasks_requeued_silent_robot_back_fallback_counted(self):
        if not self.faults:
            return  # only in faults_integration.test (a separate rostest); nothing to check here
        deadline = self.t_start + self.run_time
        # The task robot 0 carried when it stopped is requeued and delivered by another robot.
        self.assertTrue(wait_for(lambda: int(self.rec.sim_diag.get("stops fired", "0")) >= 1, 30),
                        "the stop fault never fired: %s" % self.rec.sim_diag)
        task = int(self.rec.sim_diag["stopped robot task"])
        self.assertGreaterEqual(task, 0)
        delivered = lambda: any(e[0] == TaskStatus.DELIVERED for e in self.rec.events.get(task, []))
        self.assertTrue(wait_for(delivered, max(1.0, deadline - time.time())),
                        "task %d of the stopped robot: %s" % (task, self.rec.events.get(task)))
        with self.rec.lock:
            ev = list(self.rec.events[task])
        requeues = [e for e in ev if e[0] == TaskStatus.QUEUED and "robot 0 went offline" in e[2]]
        self.assertTrue(requeues, ev)
        self.assertNotEqual(ev[-1][1], 0, "delivered by the offline robot? %s" % ev)
        # The silent robot is counted offline (with robot 0: 2), then comes back (1 again), and
        # deliveries go on after that.
        self.assertTrue(wait_for(lambda: int(self.rec.sim_diag.get("silences", "0")) >= 1, 30))
        with self.rec.lock:
            history = list(self.rec.offline_history)
        self.assertTrue(any(n >= 2 for _, n in history), "silent robot never offline: %s" % history)
        two = next(i for i, (_, n) in enumerate(history) if n >= 2)
        back = [t for t, n in history[two:] if n == 1]
        self.assertTrue(back, "silent robot never came back: %s" % history)
        self.assertTrue(wait_for(lambda: any(e[0] == TaskStatus.DELIVERED and e[3] > back[0]
                                             for evs in list(self.rec.events.values()) for e in evs),
                                 max(1.0, deadline - time.time())), "no delivery after the faults ended")
        # The slipping robot slipped, and nobody collided (checked on every state message).
        self.assertGreaterEqual(int(self.rec.sim_diag["slips"]), 1, self.rec.sim_diag)
        with self.rec.lock:
            self.assertEqual(self.rec.violations, [])
        # The planner missed its 1 us deadline: PIBT fallback ticks, counted in diagnostics.
        self.assertGreater(int(self.rec.planner_diag["fallback ticks"]), 0, self.rec.planner_diag)
        self.assertGreater(int(self.rec.planner_diag["deadline misses"]), 0, self.rec.planner_diag)
        self.assertGreater(self.rec.stats.fallback_ticks, 0)


if __name__ == "__main__":
    rospy.init_node("warehouse_test", anonymous=True)
    name = "warehouse_faults" if rospy.get_param("~faults", False) else "warehouse_integration"
    rostest.rosrun(PKG, name, WarehouseTest)
