#!/usr/bin/env python3
"""Planner restart (restart_integration.test): tasks survive a crash of the planner node.

Submits tasks over the service (accepted = journaled), kills the planner with SIGKILL once a
task is picked, and checks that the respawned planner lists every task that was open, puts the
picked ones back on the robots carrying them, and delivers all of them; robot states are checked
for shared cells, swaps and jumps throughout (the Recorder of test_warehouse.py).
"""
import os
import random
import signal
import time
import unittest

import rosgraph
import rospy
import rostest

try:
    from xmlrpc.client import ServerProxy
except ImportError:  # pragma: no cover
    from xmlrpclib import ServerProxy

from gd_rhcr_msgs.msg import MapdCells, Task, TaskStatus
from gd_rhcr_msgs.srv import ListTasks, SubmitTask
from test_warehouse import Recorder, wait_for

PKG = "gd_rhcr_planner"
PLANNER = "/gd_rhcr_planner"


def planner_pid():
    try:
        uri = rosgraph.Master("/test_restart").lookupNode(PLANNER)
        code, _msg, pid = ServerProxy(uri).getPid("/test_restart")
        return pid if code == 1 else None
    except Exception:  # not up (yet)
        return None


class RestartTest(unittest.TestCase):
    def test_tasks_survive_a_planner_crash(self):
        rec = Recorder()
        n_tasks = rospy.get_param("~tasks", 6)
        store = rospy.get_param("~store")
        self.addCleanup(lambda: os.path.exists(store) and os.remove(store))
        self.assertTrue(wait_for(lambda: len(rec.step_ticks) >= 3, 30), "no step commands")
        cells = rospy.wait_for_message("mapd_cells", MapdCells, timeout=10)
        pickups = list(zip(cells.pickup_x, cells.pickup_y))
        deliveries = list(zip(cells.delivery_x, cells.delivery_y))
        rng = random.Random(11)
        rospy.wait_for_service("submit_task", timeout=10)
        submit = rospy.ServiceProxy("submit_task", SubmitTask)
        ids = []
        for _ in range(n_tasks):
            (px, py), (dx, dy) = rng.choice(pickups), rng.choice(deliveries)
            r = submit(Task(pickup_x=px, pickup_y=py, delivery_x=dx, delivery_y=dy))
            self.assertTrue(r.accepted, r.reason)
            ids.append(r.task_id)

        def last_state(t):
            with rec.lock:
                s = rec.status.get(t, [])
                return s[-1] if s else None

        self.assertTrue(wait_for(lambda: any(last_state(t) == TaskStatus.PICKED for t in ids), 60),
                        "no task was picked within 60 s")
        listing = rospy.ServiceProxy("list_tasks", ListTasks)
        before = dict((s.task_id, (s.state, s.robot_id)) for s in listing(False).statuses)
        open_before = [t for t in ids if t in before]
        picked_before = dict((t, before[t][1]) for t in open_before if before[t][0] == TaskStatus.PICKED)
        pid = planner_pid()
        self.assertIsNotNone(pid, "cannot find the planner's pid")
        ticks_before = len(rec.step_ticks)
        os.kill(pid, signal.SIGKILL)  # a crash: no shutdown handler runs
        rospy.loginfo("killed the planner (pid %d) with %d open tasks, %d picked", pid, len(open_before),
                      len(picked_before))
        self.assertTrue(wait_for(lambda: planner_pid() not in (None, pid), 30), "the planner was not respawned")
        rospy.wait_for_service("list_tasks", timeout=30)
        # Step commands resume with the new planner's tick counter.
        self.assertTrue(wait_for(lambda: len(rec.step_ticks) > ticks_before + 5 and rec.step_ticks[-1] < 1000, 30))
        after = dict((s.task_id, (s.state, s.robot_id)) for s in listing(True).statuses)
        for t in open_before:
            self.assertIn(t, after, "task %d open before the crash is unknown after it" % t)
        for t, robot in picked_before.items():
            state, r = after[t]
            if state != TaskStatus.DELIVERED:
                self.assertEqual((state, r), (TaskStatus.PICKED, robot), "task %d lost its robot" % t)
        self.assertTrue(wait_for(lambda: all(last_state(t) == TaskStatus.DELIVERED for t in ids), 90),
                        "not delivered: %s" % [(t, last_state(t)) for t in ids if last_state(t) != TaskStatus.DELIVERED])
        with rec.lock:
            self.assertEqual(rec.violations, [])


if __name__ == "__main__":
    rospy.init_node("test_restart", anonymous=True)
    rostest.rosrun(PKG, "planner_restart", RestartTest)
