#!/usr/bin/env python3
"""Hostile input over ROS (hostile_integration.test, issue 25).

While the simulated warehouse runs (robots without an interlock), this node publishes malformed
and adversarial messages on every topic the planner subscribes to (robot_states, tasks) and
calls every service (submit_task, cancel_task, list_tasks, set_paused, emergency_stop) and the
Delivery action with bad arguments: the named cases of the issue, then a seeded random stream of
mutated messages. A node started with a misspelt parameter stops, naming it. Throughout, the planner keeps ticking; each bad input gets a reason in a
response or in /diagnostics; no accepted task is lost; no robot is commanded into an occupied
cell (fleet_sim: 0 collisions, 0 swaps, 0 moves its interlock would have stopped).
"""
import os
import random
import subprocess
import sys
import threading
import time
import unittest

import actionlib
import rospy
import rostest
from actionlib_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray
from nav_msgs.msg import OccupancyGrid

from gd_rhcr_msgs.msg import DeliveryAction, DeliveryGoal, PlannerStats, RobotState, RobotStateArray, Task, \
    TaskStatus
from gd_rhcr_msgs.srv import CancelTask, EmergencyStop, ListTasks, SetPaused, SubmitTask

PKG = "gd_rhcr_planner"
HOSTILE = "hostile"  # frame_id of our own robot_states, which the watch ignores
FINISHED = (TaskStatus.DELIVERED, TaskStatus.FAILED, TaskStatus.CANCELLED)


class Watch(object):
    def __init__(self):
        self.lock = threading.Lock()
        self.stats = None
        self.stat_times = []
        self.cells = {}
        self.queued = set()
        self.diag = {}
        self.grid = None
        rospy.Subscriber("planner_stats", PlannerStats, self.on_stats, queue_size=50)
        rospy.Subscriber("robot_states", RobotStateArray, self.on_states, queue_size=50)
        rospy.Subscriber("task_status", TaskStatus, self.on_status, queue_size=5000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag, queue_size=100)
        rospy.Subscriber("map", OccupancyGrid, self.on_map, queue_size=1)

    def on_stats(self, m):
        with self.lock:
            self.stats = m
            self.stat_times.append(time.time())

    def on_states(self, m):
        if m.header.frame_id == HOSTILE:
            return
        with self.lock:
            self.cells = {r.id: (r.x, r.y) for r in m.robots}

    def on_status(self, m):
        if m.state == TaskStatus.QUEUED:
            with self.lock:
                self.queued.add(m.task_id)

    def on_diag(self, m):
        with self.lock:
            for s in m.status:
                self.diag[s.name] = {kv.key: kv.value for kv in s.values}

    def on_map(self, m):
        with self.lock:
            self.grid = m

    def get(self, name):
        with self.lock:
            return getattr(self, name)

    def value(self, suffix, key):
        with self.lock:
            for name, values in self.diag.items():
                if name.endswith(suffix) and key in values:
                    return values[key]
        return None

    def wait(self, pred, timeout, what):
        end = time.time() + timeout
        while time.time() < end:
            if pred():
                return
            time.sleep(0.1)
        raise AssertionError("timed out waiting for " + what)


class Hostile(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.w = Watch()
        cls.n = rospy.get_param("~num_robots")
        cls.rng = random.Random(rospy.get_param("~seed", 25))
        cls.messages = rospy.get_param("~messages", 3000)
        cls.w.wait(lambda: cls.w.get("stats") is not None and cls.w.get("grid") is not None
                   and len(cls.w.get("cells")) == cls.n, 90, "the fleet running")
        for s in ("submit_task", "cancel_task", "list_tasks", "set_paused", "emergency_stop"):
            rospy.wait_for_service(s, timeout=30)
        cls.submit = rospy.ServiceProxy("submit_task", SubmitTask)
        cls.cancel = rospy.ServiceProxy("cancel_task", CancelTask)
        cls.list = rospy.ServiceProxy("list_tasks", ListTasks)
        cls.pause = rospy.ServiceProxy("set_paused", SetPaused)
        cls.estop = rospy.ServiceProxy("emergency_stop", EmergencyStop)
        cls.states_pub = rospy.Publisher("robot_states", RobotStateArray, queue_size=1000)
        cls.tasks_pub = rospy.Publisher("tasks", Task, queue_size=1000)
        cls.action = actionlib.SimpleActionClient("delivery", DeliveryAction)
        assert cls.action.wait_for_server(rospy.Duration(30))
        cls.w.wait(lambda: cls.states_pub.get_num_connections() > 0 and cls.tasks_pub.get_num_connections() > 0,
                   10, "the planner subscribed")
        g = cls.w.get("grid")
        cls.width, cls.height = g.info.width, g.info.height
        free, walls = [], []
        for y in range(cls.height):
            for x in range(cls.width):
                (free if g.data[(cls.height - 1 - y) * cls.width + x] == 0 else walls).append((x, y))
        cls.free, cls.walls = free, walls
        cls.accepted = set()  # task ids we submitted and the planner accepted

    def setUp(self):
        sys.stderr.write("hostile test: %s\n" % self.id())

    # --- helpers ---
    def states(self, robots, stamp=None):
        m = RobotStateArray()
        m.header.frame_id = HOSTILE
        m.header.stamp = stamp if stamp is not None else rospy.Time.now()
        m.robots = robots
        self.states_pub.publish(m)

    def robot(self, rid, x, y, **kw):
        r = RobotState(id=rid, x=x, y=y, task_id=-1)
        r.pose.orientation.w = 1.0
        for k, v in kw.items():
            setattr(r, k, v)
        return r

    def ignored_reason(self, text, timeout=10):
        self.w.wait(lambda: text in (self.w.value("planner", "last ignored robot report") or ""), timeout,
                    "'%s' in the planner's diagnostics" % text)

    def assert_ticking(self, seconds=2.0):
        t = self.w.get("stats").tick
        self.w.wait(lambda: self.w.get("stats").tick >= t + 3, seconds + 5, "the planner ticking")

    def task_states(self):
        r = self.list(include_finished=True)
        return {t.id: s.state for t, s in zip(r.tasks, r.statuses)}

    # --- the named cases ---
    def test_0_a_misspelt_parameter_stops_a_starting_node_naming_it(self):
        import rospkg
        maps = os.path.join(rospkg.RosPack().get_path(PKG), "maps", "warehouse_small.yaml")
        for param, value, name in (("tick_rat", 3.0, "~tick_rat"), ("planner_params", {"c_sotf": 2}, "c-sotf"),
                                   ("V", -3, "V")):
            if rospy.has_param("/misspelt"):
                rospy.delete_param("/misspelt")
            rospy.set_param("/misspelt/misspelt_planner/map", maps)
            rospy.set_param("/misspelt/misspelt_planner/task_store", "none")
            rospy.set_param("/misspelt/misspelt_planner/" + param, value)
            r = subprocess.run(["rosrun", PKG, "gd_rhcr_planner_node", "__name:=misspelt_planner", "__ns:=/misspelt"],
                               capture_output=True, text=True, timeout=60)
            self.assertNotEqual(r.returncode, 0, param)
            self.assertIn(name, r.stdout + r.stderr, param)
        rospy.delete_param("/misspelt")

    def test_1_robot_states(self):
        x0, y0 = self.w.get("cells")[0]
        self.states([self.robot(self.n + 5, x0, y0)])
        self.ignored_reason("unknown robot id")
        self.states([self.robot(7, x0, y0), self.robot(7, x0, y0)])
        self.ignored_reason("twice")
        bad = self.robot(1, *self.w.get("cells")[1])
        bad.pose.position.x = float("nan")
        self.states([bad])
        self.ignored_reason("not finite")
        bad.pose.position.x, bad.pose.orientation.z = 0.0, float("inf")
        self.states([bad])
        self.ignored_reason("not finite")
        self.states([self.robot(2, self.width + 3, 1)])
        self.ignored_reason("off the map")
        self.states([self.robot(3, *self.walls[0])])
        self.ignored_reason("obstacle")
        self.states([self.robot(4, *self.w.get("cells")[4])], stamp=rospy.Time.now() - rospy.Duration(100))
        self.ignored_reason("out of order")
        self.states([self.robot(5, *self.w.get("cells")[5], mode=77)])
        self.ignored_reason("unknown mode")
        # A free cell with a free cell two columns on: an entering cell that is on the map and free
        # but not next to the robot's cell (robot 6's own cell may have a wall two columns on).
        free = set(self.free)
        x6, y6 = next((x, y) for x, y in self.free if (x + 2, y) in free)
        self.states([self.robot(6, x6, y6, moving=True, entering_known=True, entering_x=x6 + 2, entering_y=y6)])
        self.ignored_reason("is not next to its cell")
        self.states([self.robot(6, x6, y6, moving=True, entering_known=True, entering_x=-5, entering_y=y6)])
        self.ignored_reason("entering cell (-5,%d) is off the map" % y6)
        self.states([self.robot(1000 + i, 1, 1) for i in range(100000)])
        self.ignored_reason("unknown robot id 100999")
        self.assert_ticking()

    def test_2_tasks_and_services(self):
        a, b = self.free[0], self.free[-1]
        r = self.submit(Task(id=990001, pickup_x=a[0], pickup_y=a[1], delivery_x=b[0], delivery_y=b[1]))
        self.assertTrue(r.accepted, r.reason)
        self.accepted.add(r.task_id)
        r = self.submit(Task(id=990001, pickup_x=b[0], pickup_y=b[1], delivery_x=a[0], delivery_y=a[1]))
        self.assertFalse(r.accepted)
        self.assertIn("already in use", r.reason)
        r = self.submit(Task(pickup_x=a[0], pickup_y=a[1], delivery_x=a[0], delivery_y=a[1]))
        self.assertFalse(r.accepted)
        self.assertIn("same cell", r.reason)
        r = self.submit(Task(pickup_x=2 ** 31 - 1, pickup_y=-2 ** 31, delivery_x=a[0], delivery_y=a[1]))
        self.assertFalse(r.accepted)
        self.assertIn("off the map", r.reason)
        r = self.submit(Task(pickup_x=a[0], pickup_y=a[1], delivery_x=self.walls[0][0], delivery_y=self.walls[0][1]))
        self.assertFalse(r.accepted)
        self.assertIn("obstacle", r.reason)
        self.tasks_pub.publish(Task(id=990001, pickup_x=b[0], pickup_y=b[1], delivery_x=a[0], delivery_y=a[1]))
        self.w.wait(lambda: "already in use" in (self.w.value("planner", "last rejected task") or ""), 10,
                    "a topic task with a used id named in diagnostics")
        r = self.cancel(task_id=2 ** 63)
        self.assertFalse(r.success)
        self.assertIn("unknown task", r.reason)
        r = self.pause(robot_id=self.n + 100, paused=True)
        self.assertFalse(r.success)
        self.assertIn("unknown robot", r.message)
        r = self.pause(robot_id=-(2 ** 62), paused=True)
        self.assertFalse(r.success)
        self.action.send_goal(DeliveryGoal(pickup_x=-1, pickup_y=0, delivery_x=a[0], delivery_y=a[1]))
        self.assertTrue(self.action.wait_for_result(rospy.Duration(10)))
        self.assertEqual(self.action.get_state(), GoalStatus.REJECTED)
        self.assertIn("off the map", self.action.get_result().reason)
        self.assert_ticking()

    # --- a seeded random stream of mutated messages ---
    def random_cell(self):
        k = self.rng.random()
        if k < 0.4:
            return self.rng.choice(self.free)
        if k < 0.6:
            return self.rng.choice(self.walls)
        big = 2 ** 31 - 1
        return (self.rng.randint(-big - 1, big), self.rng.randint(-big - 1, big))

    def hostile_report(self, cells):
        """A report that must be ignored: unknown ids freely, real ids only with a fault."""
        rid = self.rng.randrange(self.n)
        x, y = cells.get(rid, (0, 0))
        fault = self.rng.randrange(6)
        if fault == 0:
            return [self.robot(self.rng.randint(self.n, 2 ** 32 - 1), *self.random_cell())]
        if fault == 1:
            return [self.robot(rid, x, y), self.robot(rid, *self.random_cell())]
        r = self.robot(rid, x, y)
        if fault == 2:
            setattr(r.pose.position, self.rng.choice("xyz"), self.rng.choice([float("nan"), float("inf"), -float("inf")]))
        elif fault == 3:
            r.x, r.y = self.rng.choice(self.walls) if self.rng.random() < 0.5 else (self.width + 1, -1)
        elif fault == 4:  # moving into a cell that is not next to it, or off the map
            r.moving, r.entering_known = True, True
            r.entering_x, r.entering_y = self.rng.choice([(x + 2, y), (x, y - 2), self.rng.choice(self.walls),
                                                          (self.width + 1, -1), (x, y)])
        else:
            r.mode = self.rng.randint(6, 255)
        return [r]

    def one_random_message(self, cells):
        k = self.rng.randrange(6)
        if k == 0:
            self.states(self.hostile_report(cells) + self.hostile_report(cells),
                        stamp=rospy.Time.now() - rospy.Duration(self.rng.choice([0, 0, 50])))
        elif k == 1:
            p, d = self.random_cell(), self.random_cell()
            self.tasks_pub.publish(Task(id=self.rng.choice([0, self.rng.randint(1, 2 ** 64 - 1)]), pickup_x=p[0],
                                        pickup_y=p[1], delivery_x=d[0], delivery_y=d[1],
                                        priority=self.rng.randint(-2 ** 31, 2 ** 31 - 1)))
        elif k == 2:
            p, d = self.random_cell(), self.random_cell()
            r = self.submit(Task(id=self.rng.choice([0, 990001, self.rng.randint(1, 2 ** 64 - 1)]), pickup_x=p[0],
                                 pickup_y=p[1], delivery_x=d[0], delivery_y=d[1],
                                 priority=self.rng.randint(-2 ** 31, 2 ** 31 - 1)))
            if r.accepted:
                self.accepted.add(r.task_id)
            else:
                self.assertTrue(r.reason, "a rejection without a reason")
        elif k == 3:
            tid = self.rng.randint(2 ** 40, 2 ** 64 - 1)  # never one of the fleet's tasks
            r = self.cancel(task_id=tid)
            self.assertFalse(r.success)
            self.assertTrue(r.reason)
        elif k == 4:
            rid = self.rng.choice([self.rng.randint(self.n, 2 ** 62), self.rng.randint(-2 ** 62, -2)])
            r = self.pause(robot_id=rid, paused=self.rng.random() < 0.5)
            self.assertFalse(r.success)
            self.assertTrue(r.message)
        else:
            p = (self.width + self.rng.randint(0, 100), self.rng.randint(-100, -1))
            self.action.send_goal(DeliveryGoal(pickup_x=p[0], pickup_y=p[1], delivery_x=1, delivery_y=1))

    def test_3_random_stream(self):
        start_tick = self.w.get("stats").tick
        for i in range(self.messages):
            self.one_random_message(self.w.get("cells"))
            if i % 50 == 0:
                time.sleep(0.05)
        self.assert_ticking()
        times = self.w.get("stat_times")
        gaps = [b - a for a, b in zip(times, times[1:])]
        self.assertLess(max(gaps), 2.0, "the planner stalled for %.1f s" % max(gaps))
        self.assertGreater(self.w.get("stats").tick, start_tick + 10)

    def test_4_nothing_lost_and_no_collision(self):
        # Deliveries go on after the storm.
        delivered = self.w.get("stats").tasks_delivered
        self.w.wait(lambda: self.w.get("stats").tasks_delivered >= delivered + 3, 120, "deliveries after the storm")
        states = self.task_states()
        for tid in self.accepted | self.w.get("queued"):
            self.assertIn(tid, states, "accepted task %d vanished" % tid)
            self.assertNotIn(states[tid], (TaskStatus.FAILED, TaskStatus.CANCELLED),
                             "accepted task %d ended badly" % tid)
        for key in ("collisions", "swaps", "interlock would act"):
            self.assertEqual(self.w.value("fleet_sim: fleet", key), "0", key)


if __name__ == "__main__":
    rospy.init_node("test_hostile")
    rostest.rosrun(PKG, "hostile_integration", Hostile, sys.argv)
