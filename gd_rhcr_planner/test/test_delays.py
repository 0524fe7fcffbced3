#!/usr/bin/env python3
"""Integration test of delay-robust execution (issue 13; see delays_integration.test).

Robots with random delays, different speeds, no interlock and one robot absent: over ~run_time s
no two robots share a cell, swap cells or jump (every pair of consecutive robot_states), fleet_sim
counts no collision, no swap and no move its interlock would have stopped (and delays did happen),
the absent robot gets no command while the others keep moving and deliver at least ~deliveries
tasks, every accepted task is delivered or still open in list_tasks (none lost), and moves were
also sent between ticks (step_command_updates: the moment the robots ahead had left).
With ~action_model rotation (rotation_integration.test, issue 23: robots that take a tick per
quarter turn): every robot reports a heading, robots did turn, every command carries a heading,
and no robot was ever sent into a cell it did not face (fleet_sim never turned before a move).
"""
import threading
import time
import unittest

import rospy
import rostest
from diagnostic_msgs.msg import DiagnosticArray

from gd_rhcr_msgs.msg import RobotState, RobotStateArray, StepCommandArray, TaskStatus
from gd_rhcr_msgs.srv import ListTasks

PKG = "gd_rhcr_planner"


class DelaysTest(unittest.TestCase):
    def setUp(self):
        self.lock = threading.Lock()
        self.prev = None
        self.violations = []
        self.moved = set()
        self.commanded = set()
        self.steps = 0
        self.updates = 0
        self.accepted = set()
        self.finished = {}
        self.sim = {}
        self.no_heading = []  # reports or commands without a heading (rotation)
        self.rotation = rospy.get_param("~action_model", "mapf") == "rotation"
        rospy.Subscriber("robot_states", RobotStateArray, self.on_states, queue_size=100)
        rospy.Subscriber("step_commands", StepCommandArray, self.on_steps, queue_size=100)
        rospy.Subscriber("step_command_updates", StepCommandArray, self.on_updates, queue_size=100)
        rospy.Subscriber("task_status", TaskStatus, self.on_status, queue_size=1000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag, queue_size=100)

    def on_states(self, msg):
        cells = {r.id: (r.x, r.y) for r in msg.robots}
        with self.lock:
            if self.rotation:
                self.no_heading += ["robot %d reports heading %d" % (r.id, r.heading) for r in msg.robots
                                    if not RobotState.HEADING_EAST <= r.heading <= RobotState.HEADING_NORTH]
            if len(set(cells.values())) != len(cells):
                self.violations.append("shared cell in %s" % sorted(cells.items()))
            if self.prev is not None:
                where = {c: i for i, c in self.prev.items()}
                for i, c in cells.items():
                    p = self.prev.get(i)
                    if p is None or p == c:
                        continue
                    self.moved.add(i)
                    if abs(p[0] - c[0]) + abs(p[1] - c[1]) > 1:
                        self.violations.append("robot %d jumped %s -> %s" % (i, p, c))
                    j = where.get(c)
                    if j is not None and j != i and cells.get(j) == p:
                        self.violations.append("robots %d and %d swapped %s <-> %s" % (i, j, p, c))
            self.prev = cells

    def on_steps(self, msg):
        with self.lock:
            self.steps += 1
            for c in msg.commands:
                self.commanded.add(c.robot_id)
                if self.rotation and c.next_heading == RobotState.HEADING_NONE:
                    self.no_heading.append("command to robot %d without a heading" % c.robot_id)

    def on_updates(self, msg):
        with self.lock:
            self.updates += len(msg.commands)
            for c in msg.commands:
                self.commanded.add(c.robot_id)

    def on_status(self, msg):
        with self.lock:
            if msg.state in (TaskStatus.QUEUED, TaskStatus.ASSIGNED, TaskStatus.PICKED):
                self.accepted.add(msg.task_id)
            elif msg.state in (TaskStatus.DELIVERED, TaskStatus.CANCELLED):
                self.accepted.add(msg.task_id)
                self.finished[msg.task_id] = msg.state
            elif msg.state == TaskStatus.FAILED:
                self.finished[msg.task_id] = msg.state

    def on_diag(self, msg):
        for st in msg.status:
            if st.hardware_id == "fleet_sim":
                with self.lock:
                    self.sim = {kv.key: kv.value for kv in st.values}

    def test_delays_absent_robot_no_interlock(self):
        absent = rospy.get_param("~absent_robot", 9)
        want = rospy.get_param("~deliveries", 6)
        run_time = rospy.get_param("~run_time", 50.0)
        deadline = time.time() + 60.0
        while time.time() < deadline and not rospy.is_shutdown():
            with self.lock:
                if self.steps > 0:
                    break
            time.sleep(0.2)
        self.assertGreater(self.steps, 0, "no step command: the fleet waits for the absent robot?")
        time.sleep(run_time)
        with self.lock:
            accepted = set(self.accepted)  # tasks accepted after list_tasks are not counted
        rospy.wait_for_service("list_tasks", 10.0)
        listed = rospy.ServiceProxy("list_tasks", ListTasks)(include_finished=True)
        time.sleep(1.5)  # a late diagnostics message
        open_ids = set(t.id for t, s in zip(listed.tasks, listed.statuses)
                       if s.state in (TaskStatus.QUEUED, TaskStatus.ASSIGNED, TaskStatus.PICKED))
        with self.lock:
            self.assertEqual(self.violations[:5], [])
            self.assertTrue(self.sim, "no fleet_sim diagnostics")
            self.assertEqual(self.sim.get("interlock"), "off")
            self.assertGreater(int(self.sim.get("delays started", 0)), 5, "delays did not happen")
            self.assertEqual(int(self.sim.get("interlock would act", -1)), 0,
                             "the interlock would have stopped a commanded move")
            self.assertEqual(int(self.sim.get("collisions", -1)), 0)
            self.assertEqual(int(self.sim.get("swaps", -1)), 0)
            self.assertEqual(int(self.sim.get("invalid commands", -1)), 0)
            self.assertNotIn(absent, self.commanded, "the absent robot was commanded")
            self.assertGreater(self.updates, 0, "no move was sent between ticks")
            self.assertGreaterEqual(len(self.moved), 8, "robots that moved: %s" % sorted(self.moved))
            delivered = [t for t, s in self.finished.items() if s == TaskStatus.DELIVERED]
            self.assertGreaterEqual(len(delivered), want)
            lost = sorted(t for t in accepted if t not in self.finished and t not in open_ids)
            self.assertEqual(lost, [], "accepted tasks neither finished nor open")
            if self.rotation:
                self.assertEqual(self.no_heading[:5], [])
                self.assertGreater(int(self.sim.get("turns", 0)), 10, "robots did not turn")
                self.assertEqual(int(self.sim.get("turns before moves", -1)), 0,
                                 "a robot was sent forward into a cell it did not face")


if __name__ == "__main__":
    rospy.init_node("test_delays")
    rostest.rosrun(PKG, rospy.get_param("~test_name", "delays_integration"), DelaysTest)
