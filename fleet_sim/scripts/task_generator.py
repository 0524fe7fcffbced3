#!/usr/bin/env python3
"""Feeds MAPD tasks to the planner node on `tasks` (gd_rhcr_msgs/Task).

Pickup and delivery cells come from the planner node's latched `mapd_cells`, i.e. the core's
rule (kiva: pickups 'e', deliveries 'r'; MovingAI and map_server maps: deliveries = free cells of
the leftmost and rightmost free columns, pickups = other free cells beside an interior obstacle).
Tasks are drawn uniformly and seeded, at ~rate tasks per second, while fewer than ~max_open
tasks are open (queued, assigned or picked, tracked on `task_status`); ~max_tasks > 0 stops
after that many.
"""
import random
import threading

import rospy

from gd_rhcr_msgs.msg import MapdCells, Task, TaskStatus

FINISHED = (TaskStatus.DELIVERED, TaskStatus.FAILED, TaskStatus.CANCELLED)


class TaskGenerator(object):
    def __init__(self):
        self.rate = rospy.get_param("~rate", 1.0)
        self.max_open = rospy.get_param("~max_open", 20)
        self.max_tasks = rospy.get_param("~max_tasks", 0)
        self.rng = random.Random(rospy.get_param("~seed", 1))
        self.id_base = rospy.get_param("~id_base", 1000000)
        self.lock = threading.Lock()
        self.open = set()
        self.sent = 0
        cells = rospy.wait_for_message("mapd_cells", MapdCells)
        self.pickups = list(zip(cells.pickup_x, cells.pickup_y))
        self.deliveries = list(zip(cells.delivery_x, cells.delivery_y))
        rospy.loginfo("task_generator: %d pickups, %d deliveries (%s)", len(self.pickups),
                      len(self.deliveries), cells.rule)
        self.pub = rospy.Publisher("tasks", Task, queue_size=100)
        rospy.Subscriber("task_status", TaskStatus, self.on_status, queue_size=1000)
        rospy.Timer(rospy.Duration(1.0 / self.rate), self.on_timer)

    def on_status(self, msg):
        with self.lock:
            if msg.state in FINISHED:
                self.open.discard(msg.task_id)

    def on_timer(self, _event):
        with self.lock:
            if self.max_tasks > 0 and self.sent >= self.max_tasks:
                return
            if len(self.open) >= self.max_open or not self.pickups or not self.deliveries:
                return
            t = Task()
            t.id = self.id_base + self.sent
            t.pickup_x, t.pickup_y = self.rng.choice(self.pickups)
            t.delivery_x, t.delivery_y = self.rng.choice(self.deliveries)
            while (t.delivery_x, t.delivery_y) == (t.pickup_x, t.pickup_y):
                t.delivery_x, t.delivery_y = self.rng.choice(self.deliveries)
            t.priority = 0
            self.open.add(t.id)
            self.sent += 1
        self.pub.publish(t)


def main():
    rospy.init_node("task_generator")
    TaskGenerator()
    rospy.spin()


if __name__ == "__main__":
    main()
