#!/usr/bin/env python3
"""Feeds MAPD tasks to the planner node on `tasks` (gd_rhcr_msgs/Task).

Pickup and delivery cells come from the planner node's latched `mapd_cells`, i.e. the core's
rule (kiva: pickups 'e', deliveries 'r'; MovingAI and map_server maps: deliveries = free cells of
the leftmost and rightmost free columns, pickups = other free cells beside an interior obstacle).
Tasks are drawn uniformly and seeded, at ~rate tasks per second, while fewer than ~max_open
tasks are open (queued, assigned or picked, tracked on `task_status`); ~max_tasks > 0 stops
after that many.

Full load is the default: ~max_open -1 (default) means 2 x ~num_robots (so every robot has a
task and as many wait); without ~num_robots the robots of the first `robot_states` message are
counted. Any large number works too; a small ~max_open gives a light load. ~rate defaults to 100. ~rate may be hundreds per second: a timer runs at ~rate Hz up to
10 Hz and each event publishes up to rate/10 tasks (never more than the open-task deficit), so
the number of open tasks is topped up within 0.1 s.

Generation starts once the planner (the node that sent `mapd_cells`) subscribes to `tasks` and
every subscriber is connected, plus ~connect_delay s (default 0.5), since a task published
before a connection is up is silently dropped by ROS. Ids start at ~id_base (default 1000000), or
after the largest id at or above it the planner's `list_tasks` already holds (tasks restored
from its task store). A task that got no status at all within ~ack_timeout s (default 10) was
dropped on the way (a topic drops what is published while the planner restarts): it is sent
again with the same id, up to ~resends times (default 5; the planner ignores an id it already
holds), then taken as lost on the way: it no longer counts as open and is logged.
"""
import random
import threading
import time

import rosgraph
import rospy

from gd_rhcr_msgs.msg import MapdCells, RobotStateArray, Task, TaskStatus
from gd_rhcr_msgs.srv import ListTasks

FINISHED = (TaskStatus.DELIVERED, TaskStatus.FAILED, TaskStatus.CANCELLED)
MAX_TIMER_HZ = 10.0


class TaskGenerator(object):
    def __init__(self):
        self.rate = float(rospy.get_param("~rate", 100.0))
        self.max_open = int(rospy.get_param("~max_open", -1))
        if self.max_open < 0:
            num_robots = int(rospy.get_param("~num_robots", 0))
            if num_robots <= 0:
                try:  # count the fleet from its first report
                    num_robots = len(rospy.wait_for_message("robot_states", RobotStateArray, timeout=60.0).robots)
                except rospy.ROSException:
                    num_robots = 0
            if num_robots <= 0:
                rospy.logfatal("task_generator: ~max_open -1 needs ~num_robots > 0 (or robots on robot_states)")
                raise SystemExit(1)
            self.max_open = 2 * num_robots
        if not self.rate > 0:
            rospy.logfatal("task_generator: ~rate must be > 0 tasks per second")
            raise SystemExit(1)
        self.max_tasks = rospy.get_param("~max_tasks", 0)
        self.rng = random.Random(rospy.get_param("~seed", 1))
        self.id_base = rospy.get_param("~id_base", 1000000)
        self.ack_timeout = float(rospy.get_param("~ack_timeout", 10.0))
        self.connect_delay = float(rospy.get_param("~connect_delay", 0.5))
        self.lock = threading.Lock()
        self.open = set()
        self.unacked = {}  # task id -> (time sent, task), until its first status
        self.resent = {}  # task id -> times sent again
        self.resends = int(rospy.get_param("~resends", 5))
        self.dropped = 0
        self.sent = 0
        self.period = 1.0 / min(self.rate, MAX_TIMER_HZ)
        self.per_event = self.rate * self.period  # tasks earned per timer event (1 up to 10/s)
        self.credit = 0.0
        cells = rospy.wait_for_message("mapd_cells", MapdCells)
        self.pickups = list(zip(cells.pickup_x, cells.pickup_y))
        self.deliveries = list(zip(cells.delivery_x, cells.delivery_y))
        rospy.loginfo("task_generator: %d pickups, %d deliveries (%s); %.1f tasks/s, at most %d open",
                      len(self.pickups), len(self.deliveries), cells.rule, self.rate, self.max_open)
        self.pub = rospy.Publisher("tasks", Task, queue_size=max(100, 2 * int(self.per_event) + 10))
        rospy.Subscriber("task_status", TaskStatus, self.on_status, queue_size=10000)
        self.wait_for_planner(getattr(cells, "_connection_header", {}).get("callerid"))
        self.skip_used_ids()
        rospy.Timer(rospy.Duration(self.period), self.on_timer)

    def wait_for_planner(self, planner, timeout=30.0):
        """Until the node that sent mapd_cells (the planner) subscribes to `tasks` and every
        subscriber is connected, then ~connect_delay s more."""
        master = rosgraph.Master(rospy.get_name())
        topic = self.pub.resolved_name
        deadline = time.time() + timeout
        while not rospy.is_shutdown() and time.time() < deadline:
            try:
                subs = [n for t, nodes in master.getSystemState()[1] if t == topic for n in nodes]
            except Exception:  # master busy; try again
                subs = []
            if (planner is None or planner in subs) and subs and self.pub.get_num_connections() >= len(subs):
                break
            rospy.sleep(0.1)
        else:
            rospy.logwarn("task_generator: %s has not subscribed to %s within %.0f s; starting anyway",
                          planner, topic, timeout)
        rospy.sleep(self.connect_delay)

    def skip_used_ids(self):
        """Ids from ~id_base on may already be in the planner (tasks restored from its task store
        after a restart): start after the largest of them, so no task is rejected as a duplicate."""
        try:
            rospy.wait_for_service("list_tasks", timeout=5.0)
            resp = rospy.ServiceProxy("list_tasks", ListTasks)(include_finished=True)
        except Exception as e:  # no such service (another planner): keep ~id_base
            rospy.logwarn("task_generator: list_tasks not available (%s); ids from %d", e, self.id_base)
            return
        used = [t.id for t in resp.tasks if t.id >= self.id_base]
        if used:
            rospy.loginfo("task_generator: the planner already holds %d tasks with ids >= %d; ids from %d",
                          len(used), self.id_base, max(used) + 1)
            self.id_base = max(used) + 1

    def on_status(self, msg):
        with self.lock:
            self.unacked.pop(msg.task_id, None)
            self.resent.pop(msg.task_id, None)
            if msg.state in FINISHED:
                self.open.discard(msg.task_id)

    def make_task(self):
        t = Task()
        t.id = self.id_base + self.sent
        t.pickup_x, t.pickup_y = self.rng.choice(self.pickups)
        t.delivery_x, t.delivery_y = self.rng.choice(self.deliveries)
        while (t.delivery_x, t.delivery_y) == (t.pickup_x, t.pickup_y):
            t.delivery_x, t.delivery_y = self.rng.choice(self.deliveries)
        t.priority = 0
        return t

    def on_timer(self, _event):
        batch, again = [], []  # new tasks, tasks sent again
        now = rospy.get_time()
        with self.lock:
            if self.ack_timeout > 0:
                late = [i for i, (t, _task) in self.unacked.items() if now - t > self.ack_timeout]
                for i in late:
                    task = self.unacked[i][1]
                    if self.resent.get(i, 0) < self.resends:
                        self.resent[i] = self.resent.get(i, 0) + 1
                        self.unacked[i] = (now, task)
                        again.append(task)
                        continue
                    del self.unacked[i]
                    self.resent.pop(i, None)
                    self.open.discard(i)
                late = [i for i in late if i not in self.unacked]
                if again:
                    rospy.logwarn("task_generator: %d tasks got no status within %.0f s: sent again", len(again),
                                  self.ack_timeout)
                if late:
                    self.dropped += len(late)
                    rospy.logwarn("task_generator: %d tasks got no status within %.0f s (%d so far), "
                                  "taken as dropped: %s", len(late), self.ack_timeout, self.dropped,
                                  sorted(late)[:10])
            # Credit does not pile up while the open-task limit holds generation back.
            self.credit = min(self.credit + self.per_event, max(1.0, self.per_event))
            n = min(int(self.credit), self.max_open - len(self.open))
            if not self.pickups or not self.deliveries:
                n = 0
            if self.max_tasks > 0:
                n = min(n, self.max_tasks - self.sent)
            for _ in range(max(0, n)):
                t = self.make_task()
                self.open.add(t.id)
                self.unacked[t.id] = (now, t)
                self.sent += 1
                batch.append(t)
            self.credit -= len(batch)
        for t in again + batch:
            self.pub.publish(t)


def main():
    rospy.init_node("task_generator")
    TaskGenerator()
    rospy.spin()


if __name__ == "__main__":
    main()
