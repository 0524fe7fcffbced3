#!/usr/bin/env python3
"""two_fleets.launch, headless (two_fleets.test): each fleet runs in its own namespace with its own
map, frame and planner, and both deliver tasks; fleet_b's map frame sits beside fleet_a's."""
import threading
import time
import unittest

import rospy
import rostest
import tf2_ros
from nav_msgs.msg import OccupancyGrid

from gd_rhcr_msgs.msg import PlannerStats, StepCommandArray

PKG = "gd_rhcr_planner"


class TwoFleets(unittest.TestCase):
    def test_both_fleets_run_apart(self):
        lock = threading.Lock()
        stats, frames, robots = {}, {}, {}

        def on_stats(ns):
            def cb(msg):
                with lock:
                    stats[ns] = msg
            return cb

        def on_steps(ns):
            def cb(msg):
                with lock:
                    frames[ns] = msg.header.frame_id
                    robots[ns] = set(c.robot_id for c in msg.commands)
            return cb

        for ns in ("fleet_a", "fleet_b"):
            rospy.Subscriber("/%s/planner_stats" % ns, PlannerStats, on_stats(ns), queue_size=10)
            rospy.Subscriber("/%s/step_commands" % ns, StepCommandArray, on_steps(ns), queue_size=10)
        maps = {ns: rospy.wait_for_message("/%s/map" % ns, OccupancyGrid, timeout=60.0) for ns in ("fleet_a", "fleet_b")}
        self.assertEqual(maps["fleet_a"].header.frame_id, "fleet_a/map")
        self.assertEqual(maps["fleet_b"].header.frame_id, "fleet_b/map")
        self.assertNotEqual((maps["fleet_a"].info.width, maps["fleet_a"].info.height),
                            (maps["fleet_b"].info.width, maps["fleet_b"].info.height), "two different maps")
        topics = [t for t, _ in rospy.get_published_topics()]
        self.assertNotIn("/step_commands", topics, "nothing in the root namespace")
        deadline = time.time() + 100.0
        while time.time() < deadline:
            with lock:
                done = all(ns in stats and stats[ns].tasks_delivered >= 2 for ns in ("fleet_a", "fleet_b"))
            if done:
                break
            time.sleep(0.5)
        with lock:
            for ns in ("fleet_a", "fleet_b"):
                self.assertIn(ns, stats, "no planner_stats from %s" % ns)
                self.assertGreaterEqual(stats[ns].tasks_delivered, 2, "%s delivered too little" % ns)
                self.assertEqual(stats[ns].num_robots, 6)
                self.assertEqual(frames[ns], "%s/map" % ns)
                self.assertEqual(robots[ns], set(range(6)))
        buf = tf2_ros.Buffer()
        tf2_ros.TransformListener(buf)
        t = buf.lookup_transform("world", "fleet_b/map", rospy.Time(0), rospy.Duration(10.0))
        self.assertAlmostEqual(t.transform.translation.x, 40.0)
        # Each fleet's robots in tf under its own prefix, in its own map frame: robot 0 of
        # fleet_b is at least offset_b (40 m) right of fleet_a's origin; fleet_a's is inside its
        # map (warehouse_small, 32 m wide).
        a = buf.lookup_transform("world", "fleet_a/robot_0/base_link", rospy.Time(0), rospy.Duration(10.0))
        b = buf.lookup_transform("world", "fleet_b/robot_0/base_link", rospy.Time(0), rospy.Duration(10.0))
        self.assertLess(a.transform.translation.x, 32.0)
        self.assertGreaterEqual(b.transform.translation.x, 40.0)
        self.assertEqual(buf.lookup_transform("fleet_a/map", "fleet_a/robot_0/base_link", rospy.Time(0)).header.frame_id,
                         "fleet_a/map")
        self.assertFalse(buf.can_transform("world", "robot_0/base_link", rospy.Time(0)),
                         "an unprefixed robot frame: the fleets' frames would collide")


if __name__ == "__main__":
    rospy.init_node("two_fleets_test")
    rostest.rosrun(PKG, "two_fleets", TwoFleets)
