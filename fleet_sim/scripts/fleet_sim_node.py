#!/usr/bin/env python3
"""Simulated warehouse robots for gd_rhcr.

Waits for the latched `map` (nav_msgs/OccupancyGrid), places ~num_robots robots on distinct
free cells (seeded), and executes `step_commands`: each robot moves to its commanded cell,
taking ~move_fraction of the tick period, and switches its reported cell on arrival. Robots
publish `robot_states` (gd_rhcr_msgs/RobotStateArray) and tf map -> robot_N/base_link with a
smoothly interpolated pose. Like a real robot's safety stop, a robot never starts a move into a
cell held by a robot that is not leaving it (counted as `blocked moves` on /diagnostics; zero
when the planner's commands are followed by everyone).

Fault injection (for tests and demos):
  ~delay_robot N, ~delay_start S, ~delay_duration D: robot N ignores commands (stalls) for D s
      from S s after the first command.
  ~stop_robot N, ~stop_at S, ~stop_duration D: robot N goes offline (mode OFFLINE, does not
      move) at S s after the first command, for D s (D < 0: for good).
"""
import math
import random
import sys
import threading

import rospy
import tf2_ros
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Pose, TransformStamped
from nav_msgs.msg import OccupancyGrid

from gd_rhcr_msgs.msg import RobotState, RobotStateArray, StepCommandArray
from fleet_sim.grid_frame import GridFrame, adjacent_or_same, resolve_moves


def yaw_quaternion(yaw):
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


class Robot(object):
    def __init__(self, rid, cell):
        self.id = rid
        self.cell = cell
        self.src = cell
        self.dst = cell
        self.t0 = 0.0
        self.duration = 0.0
        self.moving = False
        self.yaw = 0.0
        self.mode = RobotState.MODE_IDLE
        self.task_id = -1


class FleetSim(object):
    def __init__(self):
        self.n = rospy.get_param("~num_robots", 10)
        self.seed = rospy.get_param("~seed", 1)
        self.move_fraction = rospy.get_param("~move_fraction", 0.6)
        self.rate = rospy.get_param("~publish_rate", 20.0)
        self.tf_enabled = rospy.get_param("~publish_tf", True)
        self.frame = rospy.get_param("~frame_id", "map")
        self.delay_robot = rospy.get_param("~delay_robot", -1)
        self.delay_start = rospy.get_param("~delay_start", 5.0)
        self.delay_duration = rospy.get_param("~delay_duration", 3.0)
        self.stop_robot = rospy.get_param("~stop_robot", -1)
        self.stop_at = rospy.get_param("~stop_at", 5.0)
        self.stop_duration = rospy.get_param("~stop_duration", -1.0)
        self.lock = threading.Lock()
        self.grid = None
        self.robots = []
        self.first_command = None
        self.blocked_moves = 0
        self.invalid_commands = 0
        self.commands_received = 0
        self.last_tick = 0

        rospy.loginfo("fleet_sim: waiting for the latched map")
        msg = rospy.wait_for_message("map", OccupancyGrid)
        self.grid = GridFrame.from_occupancy_grid(msg)
        free = self.grid.free_cells()
        if len(free) < self.n:
            rospy.logfatal("fleet_sim: %d robots do not fit on %d free cells", self.n, len(free))
            sys.exit(1)
        starts = rospy.get_param("~start_cells", [])
        if starts:
            cells = [tuple(c) for c in starts]
            if len(cells) != self.n or len(set(cells)) != self.n or not all(self.grid.is_free(*c) for c in cells):
                rospy.logfatal("fleet_sim: ~start_cells must be %d distinct free cells", self.n)
                sys.exit(1)
        else:
            cells = random.Random(self.seed).sample(free, self.n)
        self.robots = [Robot(i, c) for i, c in enumerate(cells)]
        rospy.loginfo("fleet_sim: %d robots on a %dx%d map", self.n, self.grid.width, self.grid.height)

        self.state_pub = rospy.Publisher("robot_states", RobotStateArray, queue_size=10)
        self.diag_pub = rospy.Publisher("/diagnostics", DiagnosticArray, queue_size=10)
        self.tf_pub = tf2_ros.TransformBroadcaster() if self.tf_enabled else None
        rospy.Subscriber("step_commands", StepCommandArray, self.on_commands, queue_size=10)
        rospy.Timer(rospy.Duration(1.0 / self.rate), self.on_timer)
        rospy.Timer(rospy.Duration(1.0), self.on_diagnostics)

    # --- faults -----------------------------------------------------------------------------
    def elapsed(self, now):
        return None if self.first_command is None else now - self.first_command

    def stalled(self, rid, now):
        e = self.elapsed(now)
        return (rid == self.delay_robot and e is not None and
                self.delay_start <= e < self.delay_start + self.delay_duration)

    def offline(self, rid, now):
        e = self.elapsed(now)
        if rid != self.stop_robot or e is None or e < self.stop_at:
            return False
        return self.stop_duration < 0 or e < self.stop_at + self.stop_duration

    # --- motion -----------------------------------------------------------------------------
    def advance(self, now):
        for r in self.robots:
            if r.moving and now >= r.t0 + r.duration:
                r.cell = r.dst
                r.src = r.dst
                r.moving = False

    def on_commands(self, msg):
        now = rospy.get_time()
        with self.lock:
            if self.first_command is None:
                self.first_command = now
            self.commands_received += 1
            self.last_tick = msg.tick
            self.advance(now)
            cells = [r.cell for r in self.robots]
            targets = list(cells)
            frozen = [False] * self.n
            for c in msg.commands:
                if c.robot_id >= self.n:
                    self.invalid_commands += 1
                    continue
                r = self.robots[c.robot_id]
                target = (c.next_x, c.next_y)
                if not self.offline(r.id, now):
                    r.mode = c.mode
                    r.task_id = c.task_id
                if not adjacent_or_same(r.cell, target) or not self.grid.is_free(*target):
                    self.invalid_commands += 1
                    rospy.logwarn_throttle(2.0, "fleet_sim: robot %d ignores command to %s from %s",
                                           r.id, target, r.cell)
                    continue
                targets[r.id] = target
            for r in self.robots:
                frozen[r.id] = r.moving or self.stalled(r.id, now) or self.offline(r.id, now)
            moves, blocked = resolve_moves(cells, targets, frozen)
            self.blocked_moves += len(blocked)
            duration = max(0.01, self.move_fraction * msg.tick_period)
            for i in moves:
                r = self.robots[i]
                r.src, r.dst = r.cell, targets[i]
                r.t0, r.duration, r.moving = now, duration, True
                r.yaw = math.atan2(-(r.dst[1] - r.src[1]), r.dst[0] - r.src[0])

    def pose_of(self, r, now):
        sx, sy = self.grid.world(*r.src)
        if not r.moving:
            return sx, sy
        dx, dy = self.grid.world(*r.dst)
        s = min(1.0, max(0.0, (now - r.t0) / r.duration))
        s = s * s * (3 - 2 * s)  # smoothstep: starts and stops gently
        return sx + (dx - sx) * s, sy + (dy - sy) * s

    def on_timer(self, _event):
        now = rospy.get_time()
        stamp = rospy.Time.now()
        arr = RobotStateArray()
        arr.header.stamp = stamp
        arr.header.frame_id = self.frame
        transforms = []
        with self.lock:
            self.advance(now)
            for r in self.robots:
                s = RobotState()
                s.id = r.id
                s.x, s.y = r.cell
                px, py = self.pose_of(r, now)
                q = yaw_quaternion(r.yaw)
                s.pose = Pose()
                s.pose.position.x, s.pose.position.y = px, py
                s.pose.orientation.x, s.pose.orientation.y, s.pose.orientation.z, s.pose.orientation.w = q
                s.mode = RobotState.MODE_OFFLINE if self.offline(r.id, now) else r.mode
                s.task_id = r.task_id
                s.moving = r.moving
                arr.robots.append(s)
                if self.tf_pub:
                    t = TransformStamped()
                    t.header.stamp = stamp
                    t.header.frame_id = self.frame
                    t.child_frame_id = "robot_%d/base_link" % r.id
                    t.transform.translation.x, t.transform.translation.y = px, py
                    (t.transform.rotation.x, t.transform.rotation.y,
                     t.transform.rotation.z, t.transform.rotation.w) = q
                    transforms.append(t)
        self.state_pub.publish(arr)
        if transforms:
            self.tf_pub.sendTransform(transforms)

    def on_diagnostics(self, _event):
        with self.lock:
            st = DiagnosticStatus()
            st.name = rospy.get_name() + ": fleet"
            st.hardware_id = "fleet_sim"
            st.level = DiagnosticStatus.OK if self.blocked_moves == 0 else DiagnosticStatus.WARN
            st.message = "%d robots" % self.n
            for k, v in (("robots", self.n), ("commands received", self.commands_received),
                         ("last tick", self.last_tick), ("blocked moves", self.blocked_moves),
                         ("invalid commands", self.invalid_commands)):
                st.values.append(KeyValue(key=k, value=str(v)))
        arr = DiagnosticArray()
        arr.header.stamp = rospy.Time.now()
        arr.status.append(st)
        self.diag_pub.publish(arr)


def main():
    rospy.init_node("fleet_sim")
    FleetSim()
    rospy.spin()


if __name__ == "__main__":
    main()
