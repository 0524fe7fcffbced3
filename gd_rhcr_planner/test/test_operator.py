#!/usr/bin/env python3
"""The operator's fleet manager in namespace fleet_a (operator_integration.test).

Checks: topics live under the namespace; PlannerStats carries the planner's and the dispatcher's
figures as fields; /diagnostics comes from diagnostic_updater (planner health, tick rate, tick
stamps) and the planner status clears when the emergency stop is released; `rosrun
dynamic_reconfigure dynparam set` changes V, H and c_soft between ticks (nonsense is refused) with
no task lost; pausing one robot and the whole fleet holds them with mode PAUSED and resume frees
them; an unknown robot is refused with a reason; the emergency stop holds every robot (mode
STOPPED), keeps every task, and deliveries continue after the release.
"""
import re
import sys
import subprocess
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray
from visualization_msgs.msg import MarkerArray

from gd_rhcr_msgs.msg import PlannerStats, RobotState, RobotStateArray, StepCommandArray, TaskStatus
from gd_rhcr_msgs.srv import EmergencyStop, ListTasks, SetPaused

PKG = "gd_rhcr_planner"
NODE = "/fleet_a/gd_rhcr_planner"


class Watch(object):
    def __init__(self):
        self.lock = threading.RLock()  # wait() predicates call status(), which locks again
        self.stats = None
        self.cmds = None
        self.cells = {}
        self.diag = {}
        self.failed = []
        rospy.Subscriber("planner_stats", PlannerStats, self.on_stats, queue_size=10)
        rospy.Subscriber("step_commands", StepCommandArray, self.on_cmds, queue_size=10)
        rospy.Subscriber("robot_states", RobotStateArray, self.on_states, queue_size=10)
        rospy.Subscriber("task_status", TaskStatus, self.on_status, queue_size=1000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag, queue_size=100)

    def on_stats(self, m):
        with self.lock:
            self.stats = m

    def on_cmds(self, m):
        with self.lock:
            self.cmds = m

    def on_states(self, m):
        with self.lock:
            self.cells = {r.id: (r.x, r.y, r.moving) for r in m.robots}

    def on_status(self, m):
        if m.state == TaskStatus.FAILED:
            with self.lock:
                self.failed.append((m.task_id, m.reason))

    def on_diag(self, m):
        with self.lock:
            for s in m.status:
                self.diag[s.name] = (s, time.time())

    def get(self, name):
        with self.lock:
            return getattr(self, name)

    def wait(self, pred, timeout, what):
        end = time.time() + timeout
        while time.time() < end:
            with self.lock:
                if pred(self):
                    return
            time.sleep(0.1)
        raise AssertionError("timed out waiting for " + what)

    def status(self, suffix):
        with self.lock:
            for name, (s, t) in self.diag.items():
                if name.endswith(suffix):
                    return s
        return None


def modes(w):
    return {c.robot_id: c.mode for c in w.cmds.commands} if w.cmds else {}


def still(w, robots, seconds):
    """Cells of `robots` over `seconds`; True when none moved."""
    start = {r: w.get("cells")[r][:2] for r in robots}
    end = time.time() + seconds
    while time.time() < end:
        now = w.get("cells")
        if any(now[r][:2] != start[r] for r in robots):
            return False
        time.sleep(0.05)
    return True


def dynparam(*args):
    return subprocess.run(["rosrun", "dynamic_reconfigure", "dynparam"] + list(args),
                          capture_output=True, text=True, timeout=60)


class Operator(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.w = Watch()
        cls.n = rospy.get_param("~num_robots")
        cls.w.wait(lambda w: w.stats is not None and w.stats.tasks_delivered >= 2, 90, "two deliveries")
        for s in ("set_paused", "emergency_stop", "list_tasks"):
            rospy.wait_for_service(s, timeout=30)
        cls.pause = rospy.ServiceProxy("set_paused", SetPaused)
        cls.estop = rospy.ServiceProxy("emergency_stop", EmergencyStop)
        cls.list = rospy.ServiceProxy("list_tasks", ListTasks)

    def open_ids(self):
        return set(t.id for t, s in zip(*self._list()) if s.state not in (3, 4, 5))

    def _list(self):
        r = self.list(include_finished=True)
        return r.tasks, r.statuses

    def states_of(self):
        t, s = self._list()
        return {a.id: b.state for a, b in zip(t, s)}

    def assert_no_task_lost(self, before):
        after = self.states_of()
        for tid in before:
            self.assertIn(tid, after, "task %d vanished" % tid)
            self.assertNotIn(after[tid], (TaskStatus.FAILED, TaskStatus.CANCELLED), "task %d ended badly" % tid)

    def setUp(self):
        sys.stderr.write("operator test: %s\n" % self.id())

    def test_1_namespace_stats_and_markers(self):
        topics = [t for t, _ in rospy.get_published_topics()]
        for t in ("/fleet_a/step_commands", "/fleet_a/planner_stats", "/fleet_a/fleet_markers", "/fleet_a/map"):
            self.assertIn(t, topics)
        self.assertNotIn("/step_commands", topics)
        st = self.w.get("stats")
        self.assertEqual(st.dispatcher, "batch")
        self.assertIn("V=2", st.planner_config)
        # GD-RHCR's step budget follows the plan deadline (0.7 x the 0.2 s tick): 90% of it.
        self.assertIn("step_budget=0.126", st.planner_config)
        self.assertEqual(st.planner, "gd-rhcr")
        self.assertGreater(st.solver_calls + st.cache_reuses + st.threshold_fallbacks, 0, "GD-RHCR counters as fields")
        self.assertGreaterEqual(st.dispatch_robots, 0)
        self.w.wait(lambda w: w.stats.deliveries_per_minute > 0, 30, "deliveries per minute")
        # A late subscriber gets the whole picture, one namespace per layer.
        got = rospy.wait_for_message("fleet_markers", MarkerArray, timeout=10)
        ns = set(m.ns for m in got.markers)
        for layer in ("robots", "paths", "stations", "tasks", "overlay", "groups", "labels"):
            self.assertIn(layer, ns)
        overlay = [m for m in got.markers if m.ns == "overlay"][0]
        self.assertIn("deliveries/min", overlay.text)
        self.assertIn("open tasks", overlay.text)

    def test_2_diagnostic_updater(self):
        self.w.wait(lambda w: self.w.status("gd_rhcr_planner: tick rate") is not None, 15, "tick rate status")
        planner = self.w.status("gd_rhcr_planner: planner")
        self.assertIsNotNone(planner, "diagnostic_updater's planner status")
        self.assertIn("gd_rhcr_fleet", planner.hardware_id)
        keys = {kv.key: kv.value for kv in planner.values}
        self.assertIn("planner config", keys)
        self.assertIn("deliveries per minute", keys)
        self.assertIsNotNone(self.w.status("gd_rhcr_planner: tick stamps"))
        # The tick runs at its rate once the fleet is up (the frequency status reads OK).
        self.w.wait(lambda w: self.w.status("gd_rhcr_planner: tick rate").level == 0, 20, "tick rate OK")

    def test_3_dynamic_reconfigure(self):
        before = self.open_ids()
        delivered = self.w.get("stats").tasks_delivered
        r = dynparam("set", NODE, "V", "3")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.w.wait(lambda w: "V=3 " in w.stats.planner_config and w.stats.reconfigures >= 1, 15, "V=3 applied")
        r = dynparam("set", NODE, "{'H': 10, 'c_soft': 2.0}")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.w.wait(lambda w: "H=10 " in w.stats.planner_config and "c_soft=2 " in w.stats.planner_config, 15, "H, c_soft")
        # Nonsense is put back: a plan deadline longer than the tick period (0.2 s).
        dynparam("set", NODE, "plan_deadline", "5.0")
        time.sleep(1.0)
        got = dynparam("get", NODE)
        m = re.search(r"'plan_deadline': ([0-9.eE+-]+)", got.stdout)
        self.assertIsNotNone(m, got.stdout)
        self.assertLessEqual(float(m.group(1)), 0.2, "a deadline past the tick period was accepted")
        # An unknown parameter is refused, naming it; an out-of-range planner parameter and an
        # unknown solver are rejected by the node (checked against the parameter table), the
        # old value kept.
        r = dynparam("set", NODE, "V_typo", "3")  # dynparam prints the error and exits 0
        self.assertIn("don't know parameter: V_typo", r.stdout + r.stderr)
        dynparam("set", NODE, "{'V': -4, 'solver': 'magic'}")
        time.sleep(1.0)
        got = dynparam("get", NODE).stdout
        self.assertIn("'V': 3", got, "an out-of-range V replaced the live value")
        self.assertIn("'solver': 'pbs'", got, "an unknown solver replaced the live one")
        self.assertIn("V=3 ", self.w.get("stats").planner_config)
        # A valid deadline: the planner is rebuilt with the step budget that follows it.
        r = dynparam("set", NODE, "plan_deadline", "0.1")
        self.assertEqual(r.returncode, 0, r.stderr)
        self.w.wait(lambda w: "step_budget=0.09" in w.stats.planner_config, 15, "step budget follows the deadline")
        # The fleet keeps working with no task lost.
        self.w.wait(lambda w: w.stats.tasks_delivered >= delivered + 2, 60, "deliveries after reconfigure")
        self.assert_no_task_lost(before)
        self.assertEqual(self.w.get("failed"), [])
        dynparam("set", NODE, "{'V': 2, 'H': 20, 'c_soft': 1.0, 'plan_deadline': 0.14}")

    def test_4_pause_one_robot(self):
        res = self.pause(robot_id=99, paused=True)
        self.assertFalse(res.success)
        self.assertIn("unknown robot id 99", res.message)
        res = self.pause(robot_id=0, paused=True)
        self.assertTrue(res.success, res.message)
        self.w.wait(lambda w: modes(w).get(0) == RobotState.MODE_PAUSED, 5, "robot 0 PAUSED")
        time.sleep(1.0)  # a move under way ends
        self.assertTrue(still(self.w, [0], 2.0), "a paused robot moved")
        self.assertNotEqual(modes(self.w).get(1), RobotState.MODE_PAUSED)
        res = self.pause(robot_id=0, paused=False)
        self.assertTrue(res.success)
        self.w.wait(lambda w: modes(w).get(0) != RobotState.MODE_PAUSED, 5, "robot 0 resumed")

    def test_5_pause_fleet(self):
        before = self.open_ids()
        res = self.pause(robot_id=-1, paused=True)
        self.assertTrue(res.success)
        self.assertIn("fleet paused", res.message)
        self.w.wait(lambda w: set(modes(w).values()) == {RobotState.MODE_PAUSED}, 5, "all PAUSED")
        time.sleep(1.0)
        self.assertTrue(still(self.w, range(self.n), 2.0), "a robot moved while the fleet was paused")
        self.pause(robot_id=-1, paused=False)
        self.w.wait(lambda w: RobotState.MODE_PAUSED not in modes(w).values(), 5, "fleet resumed")
        self.assert_no_task_lost(before)

    def test_6_emergency_stop(self):
        before = self.open_ids()
        self.assertTrue(self.estop(engage=True).success)
        self.w.wait(lambda w: set(modes(w).values()) == {RobotState.MODE_STOPPED}, 5, "all STOPPED")
        time.sleep(1.0)
        delivered = self.w.get("stats").tasks_delivered
        self.assertTrue(still(self.w, range(self.n), 3.0), "a robot moved during the emergency stop")
        self.assertTrue(self.w.get("stats").emergency_stop)
        self.w.wait(lambda w: self.w.status("gd_rhcr_planner: planner").level == 1 and
                    "emergency stop" in self.w.status("gd_rhcr_planner: planner").message, 5, "WARN status")
        held_open = self.open_ids()
        time.sleep(1.0)
        self.assertEqual(self.open_ids(), held_open, "open tasks changed during the emergency stop")
        self.assertTrue(self.estop(engage=False).success)
        self.w.wait(lambda w: "emergency stop" not in self.w.status("gd_rhcr_planner: planner").message, 10,
                    "the status clears")
        self.w.wait(lambda w: w.stats.tasks_delivered > delivered, 60, "deliveries after the release")
        self.assert_no_task_lost(before)
        self.assertEqual(self.w.get("failed"), [])


if __name__ == "__main__":
    rospy.init_node("operator_test")
    rostest.rosrun(PKG, "operator_integration", Operator)
