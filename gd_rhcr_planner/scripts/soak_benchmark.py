#!/usr/bin/env python3
"""Soak benchmark: watches a running fleet (planner node + robots + task source) for a long run
and checks that nothing unsafe happens and no task is lost.

    roslaunch gd_rhcr_planner soak.launch num_robots:=200 duration:=1800 output:=/tmp/soak.json
    rosrun gd_rhcr_planner soak_benchmark.py _robot_steps:=100000 _output:=/tmp/soak.json

Checks, over every consecutive pair of `robot_states` (RobotStateArray) messages: two robots
reporting one cell (vertex collision), two robots swapping cells (edge collision), a robot
moving more than one cell (jump), and a robot that reported OFFLINE at rest moving while still
OFFLINE. A robot missing from a message (a robot that stopped reporting) is taken to be at its
last reported cell if that report was at rest, and its first report after it comes back is
compared with that cell. Each of these is printed as a FAILURE.

Tasks (`task_status`): accepted = every task id seen QUEUED (or later states); delivered, failed
(with reasons), cancelled; rejected = FAILED without being accepted. At the end the planner's
`list_tasks` (include_finished) gives the open tasks; lost = accepted tasks neither delivered,
failed, cancelled, nor open. A failed task is accounted for (the planner told its client why);
it is reported with its reason, not counted as lost. Tasks seen on `tasks` that never got any
status are reported as unacknowledged (dropped before the planner saw them).

Also: ticks and robot-steps (robots x ticks, from `step_commands`), planner_stats (tick callback
and plan time percentiles, overruns, skipped ticks, forced waits), the last planner and
fleet_sim /diagnostics values, and the planner node's resident memory (VmRSS of the pid the node
reports through the ROS master/XML-RPC getPid; sampled every ~memory_period s; start = at the
first step command, end, peak, the kernel's VmHWM, and a linear growth rate over the second
half of the run, after the warm-up in which the open tasks pile up). A planner that dies and is
respawned is followed: its successor's pid is found and sampled, and the restarts are counted.

Stops after ~robot_steps robot-steps (default 100000) or ~duration s (default 0 = no limit) of
wall time from the first step command, whichever comes first, or when no step command came for
~stall_timeout s (a failure). Prints a summary block, writes it as JSON to ~output if set, and
exits non-zero on any collision, swap, jump, offline move, lost or unacknowledged task, stall,
or when no step command ever came.

Parameters: ~planner_node (/gd_rhcr_planner), ~fleet_sim_node (/fleet_sim),
~task_generator_node (/task_generator) (their parameters go into the summary), ~robot_steps,
~duration, ~output, ~stall_timeout (60), ~startup_timeout (180), ~memory_period (1.0),
~progress_period (30; 0 = quiet), ~warm (300 s: when rss_warm_mb is sampled), ~settle (2.0 s to wait for late task_status messages after
list_tasks), ~max_examples (20 FAILURE lines printed per kind).
"""
import json
import math
import os
import sys
import threading
import time

try:
    from xmlrpc.client import ServerProxy
except ImportError:  # pragma: no cover
    from xmlrpclib import ServerProxy

import rosgraph
import rospy
from diagnostic_msgs.msg import DiagnosticArray

from gd_rhcr_msgs.msg import PlannerStats, RobotState, RobotStateArray, StepCommandArray, Task, TaskStatus
from gd_rhcr_msgs.srv import ListTasks

FINISHED = (TaskStatus.DELIVERED, TaskStatus.FAILED, TaskStatus.CANCELLED)
ACCEPTED = (TaskStatus.QUEUED, TaskStatus.ASSIGNED, TaskStatus.PICKED, TaskStatus.DELIVERED,
            TaskStatus.CANCELLED)
STATE_NAMES = {TaskStatus.QUEUED: "queued", TaskStatus.ASSIGNED: "assigned", TaskStatus.PICKED: "picked",
               TaskStatus.DELIVERED: "delivered", TaskStatus.FAILED: "failed",
               TaskStatus.CANCELLED: "cancelled"}


def pct(values, q):
    v = sorted(values)
    return v[min(len(v) - 1, int(round(q / 100.0 * (len(v) - 1))))] if v else None


def manhattan(a, b):
    return abs(a[0] - b[0]) + abs(a[1] - b[1])


def node_pid(master, node):
    """The pid of a ROS node, through the master's lookupNode and the node's getPid."""
    uri = master.lookupNode(node)
    code, _msg, pid = ServerProxy(uri).getPid(rospy.get_name())
    if code != 1:
        raise RuntimeError("getPid failed")
    return int(pid), uri


def read_status_kb(pid, key):
    try:
        with open("/proc/%d/status" % pid) as f:
            for line in f:
                if line.startswith(key + ":"):
                    return int(line.split()[1])
    except (IOError, OSError, ValueError):
        return None
    return None


def linear_slope(points):
    """Least-squares slope of (t, y) points, None with fewer than 3."""
    if len(points) < 3:
        return None
    n = float(len(points))
    mt = sum(p[0] for p in points) / n
    my = sum(p[1] for p in points) / n
    var = sum((p[0] - mt) ** 2 for p in points)
    if var <= 0:
        return None
    return sum((p[0] - mt) * (p[1] - my) for p in points) / var


class Soak(object):
    def __init__(self):
        self.planner_node = rospy.get_param("~planner_node", "/gd_rhcr_planner")
        self.fleet_sim_node = rospy.get_param("~fleet_sim_node", "/fleet_sim")
        self.task_generator_node = rospy.get_param("~task_generator_node", "/task_generator")
        self.robot_steps_target = int(rospy.get_param("~robot_steps", 100000))
        self.duration = float(rospy.get_param("~duration", 0.0))
        self.output = rospy.get_param("~output", "")
        self.stall_timeout = float(rospy.get_param("~stall_timeout", 60.0))
        self.startup_timeout = float(rospy.get_param("~startup_timeout", 180.0))
        self.memory_period = float(rospy.get_param("~memory_period", 1.0))
        self.progress_period = float(rospy.get_param("~progress_period", 30.0))
        self.settle = float(rospy.get_param("~settle", 2.0))
        self.max_examples = int(rospy.get_param("~max_examples", 20))
        self.warm = float(rospy.get_param("~warm", 300.0))  # s after the first step: rss_warm_mb
        self.lock = threading.Lock()
        self.t_launch = time.time()
        self.t_first = None  # wall time of the first step command
        self.t_last_step = None
        self.finished = False

        # Robot states.
        self.state_msgs = 0
        self.prev = None  # id -> (cell, moving) of the previous message
        self.prev_seq = None
        self.seq_gaps = 0
        self.last_known = {}  # id -> (cell, moving) of its last report
        self.absent_max = 0
        self.absent_now = set()
        self.reappeared = 0
        self.collisions = 0
        self.swaps = 0
        self.jumps = 0
        self.offline_moves = 0
        self.active_collisions = set()
        self.offline_cell = {}
        self.examples = {"collision": 0, "swap": 0, "jump": 0, "offline move": 0}
        self.num_robots_seen = 0

        # Step commands and planner stats.
        self.ticks = 0
        self.robot_steps = 0
        self.first_tick = None
        self.last_tick = None
        self.tick_gaps = 0
        self.max_robots = 0
        self.stats_first = None
        self.stats_last = None
        self.step_times = []
        self.plan_times = []
        self.forced_waits = 0
        self.max_tasks_open = 0
        self.busy = []
        self.max_offline = None  # PlannerStats.offline_robots, when the message has it

        # Tasks.
        self.task_states = {}  # id -> list of states seen
        self.task_states_pre = {}  # id -> states received before the list_tasks snapshot
        self.t_snapshot = None  # when list_tasks was asked
        self.late_tasks = set()  # first seen after the snapshot (not accounted)
        self.baseline = None  # id -> state from list_tasks at the first step command (restored tasks)
        self.fail_reasons = {}
        self.sent = {}  # id -> wall time first seen on `tasks`
        self.status_after_finish = 0

        # Diagnostics.
        self.planner_diag = {}
        self.sim_diag = {}
        self.planner_diag_errors = 0
        self.planner_diag_messages = {}

        # Memory.
        self.pid = None
        self.pids = []  # every planner pid seen, in order (a respawned planner adds one)
        self.mem_samples = []  # (wall time, rss kB)
        self.mem_start = None
        self.mem_error = ""

        rospy.Subscriber("robot_states", RobotStateArray, self.on_states, queue_size=2000, buff_size=1 << 24)
        rospy.Subscriber("step_commands", StepCommandArray, self.on_steps, queue_size=1000, buff_size=1 << 24)
        rospy.Subscriber("planner_stats", PlannerStats, self.on_stats, queue_size=1000)
        rospy.Subscriber("task_status", TaskStatus, self.on_status, queue_size=100000)
        rospy.Subscriber("tasks", Task, self.on_task, queue_size=100000)
        rospy.Subscriber("/diagnostics", DiagnosticArray, self.on_diag, queue_size=100)

    # --- failures -----------------------------------------------------------------------------
    def failure(self, kind, text):
        self.examples[kind] += 1
        if self.examples[kind] <= self.max_examples:
            rospy.logerr("FAILURE %s: %s", kind, text)
        elif self.examples[kind] == self.max_examples + 1:
            rospy.logerr("FAILURE %s: more of these, not printed", kind)

    # --- callbacks ----------------------------------------------------------------------------
    def on_states(self, msg):
        with self.lock:
            if self.finished:
                return
            self.state_msgs += 1
            seq = msg.header.seq
            if self.prev_seq is not None and seq != self.prev_seq + 1:
                self.seq_gaps += 1
            self.prev_seq = seq
            cur = {}
            for r in msg.robots:
                cur[r.id] = ((r.x, r.y), r.moving)
            self.num_robots_seen = max(self.num_robots_seen, len(cur))
            # Robots that stopped reporting stand where they last reported (if at rest).
            absent = set(i for i in self.last_known if i not in cur)
            self.absent_max = max(self.absent_max, len(absent))
            occupants = {}
            for i, (c, _m) in cur.items():
                occupants.setdefault(c, []).append(i)
            for i in absent:
                c, moving = self.last_known[i]
                if not moving:
                    occupants.setdefault(c, []).append(i)
            now_collisions = set()
            for c, ids in occupants.items():
                if len(ids) > 1:
                    ids = tuple(sorted(ids))
                    now_collisions.add((ids, c))
                    if (ids, c) not in self.active_collisions:
                        self.collisions += 1
                        self.failure("collision", "robots %s report cell %s (msg seq %d%s)" % (
                            list(ids), c, seq, ", some not reporting" if any(i in absent for i in ids) else ""))
            self.active_collisions = now_collisions
            if self.prev is not None:
                where = {}
                for i, (c, _m) in self.prev.items():
                    where[c] = i
                for i, (c, _m) in cur.items():
                    p = self.prev.get(i)
                    if p is None:
                        p = self.last_known.get(i)
                        if p is None:
                            continue
                        self.reappeared += 1
                    p = p[0]
                    if manhattan(p, c) > 1:
                        self.jumps += 1
                        self.failure("jump", "robot %d %s -> %s (msg seq %d)" % (i, p, c, seq))
                    j = where.get(c)
                    if j is not None and j != i and c != p and j in cur and cur[j][0] == p:
                        if i < j:  # count each swap once
                            self.swaps += 1
                            self.failure("swap", "robots %d and %d swapped %s <-> %s (msg seq %d)" % (i, j, p, c, seq))
            for r in msg.robots:
                if r.mode == RobotState.MODE_OFFLINE:
                    if not r.moving:
                        first = self.offline_cell.setdefault(r.id, (r.x, r.y))
                        if first != (r.x, r.y):
                            self.offline_moves += 1
                            self.failure("offline move", "robot %d moved %s -> %s while OFFLINE" % (r.id, first, (r.x, r.y)))
                            self.offline_cell[r.id] = (r.x, r.y)
                else:
                    self.offline_cell.pop(r.id, None)
            self.absent_now = absent
            self.last_known.update(cur)
            self.prev = cur

    def on_steps(self, msg):
        now = time.time()
        with self.lock:
            if self.finished:
                return
            if self.t_first is None:
                self.t_first = now
                self.first_tick = msg.tick
                self.sample_memory_locked(now, start=True)
            elif self.last_tick is not None and msg.tick > self.last_tick + 1:
                self.tick_gaps += msg.tick - self.last_tick - 1
            self.t_last_step = now
            self.last_tick = msg.tick
            self.ticks += 1
            self.robot_steps += len(msg.commands)
            self.max_robots = max(self.max_robots, len(msg.commands))

    def on_stats(self, msg):
        with self.lock:
            if self.finished:
                return
            if self.stats_first is None:
                self.stats_first = msg
            self.stats_last = msg
            self.step_times.append(msg.step_time)
            self.plan_times.append(msg.plan_time)
            self.forced_waits += msg.forced_waits
            self.max_tasks_open = max(self.max_tasks_open, msg.tasks_queued + msg.tasks_active)
            self.busy.append(msg.tasks_active)  # robots with a task (assigned or picked)
            off = getattr(msg, "offline_robots", None)
            if off is not None:
                self.max_offline = max(self.max_offline or 0, off)

    def on_status(self, msg):
        with self.lock:
            if self.t_snapshot is not None and msg.task_id not in self.task_states:
                self.late_tasks.add(msg.task_id)  # arrived after the snapshot: not judged
                return
            if self.t_snapshot is None:
                self.task_states_pre.setdefault(msg.task_id, []).append(msg.state)
            states = self.task_states.setdefault(msg.task_id, [])
            if states and states[-1] in FINISHED:
                self.status_after_finish += 1
            states.append(msg.state)
            if msg.state == TaskStatus.FAILED:
                self.fail_reasons[msg.task_id] = msg.reason

    def on_task(self, msg):
        with self.lock:
            if msg.id != 0 and msg.id not in self.sent:
                self.sent[msg.id] = time.time()

    def on_diag(self, msg):
        with self.lock:
            for s in msg.status:
                d = dict((kv.key, kv.value) for kv in s.values)
                if s.hardware_id == "fleet_sim":
                    self.sim_diag = d
                elif s.hardware_id.startswith("gd_rhcr_fleet") and s.name.endswith(": planner"):
                    self.planner_diag = d
                    if s.level >= 2:
                        self.planner_diag_errors += 1
                    if s.level >= 1:
                        self.planner_diag_messages[s.message] = self.planner_diag_messages.get(s.message, 0) + 1

    # --- memory -------------------------------------------------------------------------------
    def find_pid(self):
        try:
            pid, uri = node_pid(rosgraph.Master(rospy.get_name()), self.planner_node)
        except Exception as e:  # not up yet, or gone
            self.mem_error = "no pid for %s: %s" % (self.planner_node, e)
            return
        host = uri.split("//", 1)[-1].split(":", 1)[0]
        if read_status_kb(pid, "VmRSS") is None:
            self.mem_error = "pid %d of %s (%s) is not readable here" % (pid, self.planner_node, host)
            return
        self.pid = pid
        if not self.pids or self.pids[-1] != pid:
            self.pids.append(pid)
        self.mem_error = ""

    def sample_memory_locked(self, now, start=False):
        if self.pid is None:
            return
        rss = read_status_kb(self.pid, "VmRSS")
        if rss is None:  # the planner died: look for its successor (respawn)
            self.mem_error = "planner pid %d vanished" % self.pid
            self.pid = None
            return
        self.mem_samples.append((now, rss))
        if start:
            self.mem_start = rss

    def rss_at(self, seconds):
        """The first memory sample at least `seconds` after the first step command, in kB."""
        if self.t_first is None:
            return None
        for t, kb in self.mem_samples:
            if t - self.t_first >= seconds:
                return kb
        return None

    # --- run ----------------------------------------------------------------------------------
    def run(self):
        rate = rospy.Rate(5)
        next_mem = 0.0
        next_progress = time.time() + self.progress_period
        reason = None
        while not rospy.is_shutdown():
            now = time.time()
            if self.pid is None and now >= next_mem:
                self.find_pid()
            with self.lock:
                if now >= next_mem:
                    self.sample_memory_locked(now)
                    next_mem = now + self.memory_period
                started = self.t_first is not None
                if started and self.robot_steps >= self.robot_steps_target:
                    reason = "robot_steps reached"
                elif started and self.duration > 0 and now - self.t_first >= self.duration:
                    reason = "duration reached"
                elif started and now - self.t_last_step > self.stall_timeout:
                    reason = "STALL: no step command for %.0f s" % self.stall_timeout
                elif not started and now - self.t_launch > self.startup_timeout:
                    reason = "STALL: no step command within %.0f s of start" % self.startup_timeout
                if self.progress_period > 0 and now >= next_progress and started:
                    next_progress = now + self.progress_period
                    rss = self.mem_samples[-1][1] / 1024.0 if self.mem_samples else float("nan")
                    rospy.loginfo("soak: %.0f s, %d ticks, %d robot-steps, %d tasks delivered, "
                                  "collisions %d swaps %d jumps %d, rss %.1f MB",
                                  now - self.t_first, self.ticks, self.robot_steps,
                                  sum(1 for s in self.task_states.values() if TaskStatus.DELIVERED in s),
                                  self.collisions, self.swaps, self.jumps, rss)
            if reason:
                break
            if started and self.baseline is None:
                listed, err = self.list_tasks()
                self.baseline = listed if listed is not None else {}
                if err:
                    rospy.logwarn("soak: %s", err)
            rate.sleep()
        if reason is None:
            reason = "shut down"
        return self.finish(reason)

    def list_tasks(self):
        name = self.planner_node.rstrip("/")
        ns = name.rsplit("/", 1)[0]
        srv = (ns + "/list_tasks") if ns else "/list_tasks"
        try:
            rospy.wait_for_service(srv, timeout=10.0)
            resp = rospy.ServiceProxy(srv, ListTasks)(include_finished=True)
            return dict((s.task_id, s.state) for s in resp.statuses), ""
        except Exception as e:
            return None, "list_tasks (%s) failed: %s" % (srv, e)

    def params_of(self, node):
        try:
            p = rospy.get_param(node)
        except KeyError:
            return {}
        return dict((k, v) for k, v in p.items() if not isinstance(v, (dict, list)))

    def finish(self, reason):
        t_end = time.time()
        with self.lock:
            self.finished = True  # freeze robot and tick figures now
            self.sample_memory_locked(t_end)
            self.t_snapshot = time.time()
        listed, list_error = self.list_tasks()
        time.sleep(self.settle)  # statuses sent before the snapshot may still be on their way
        hwm = read_status_kb(self.pid, "VmHWM") if self.pid else None
        with self.lock:
            summary = self.summary(reason, t_end, listed, list_error, hwm)
        self.print_summary(summary)
        if self.output:
            d = os.path.dirname(os.path.abspath(self.output))
            if not os.path.isdir(d):
                os.makedirs(d)
            with open(self.output, "w") as f:
                json.dump(summary, f, indent=2, sort_keys=True)
            rospy.loginfo("soak: summary written to %s", self.output)
        return 0 if summary["pass"] else 1

    def summary(self, reason, t_end, listed, list_error, hwm):
        wall = (t_end - self.t_first) if self.t_first else 0.0
        # Tasks.
        accepted, delivered, failed, cancelled, opened, lost, rejected = set(), set(), set(), set(), set(), set(), set()
        unseen_final = 0
        mismatches = 0
        finished_unlisted = 0
        for tid, states in self.task_states.items():
            if any(s in ACCEPTED for s in states):
                accepted.add(tid)
            elif TaskStatus.FAILED in states:
                rejected.add(tid)
        baseline_open = set(tid for tid, st in (self.baseline or {}).items() if st not in FINISHED)
        accepted |= baseline_open  # open when we started (e.g. restored from the planner's task store)
        if listed:
            for tid, st in listed.items():  # statuses we missed (e.g. before we subscribed)
                if tid not in self.task_states and tid not in rejected and st != TaskStatus.FAILED:
                    accepted.add(tid)
        for tid in accepted:
            states = self.task_states.get(tid, [])
            seen_final = [s for s in states if s in FINISHED]
            final = seen_final[-1] if seen_final else None
            lst = listed.get(tid) if listed else None
            if final is None and lst is not None and lst in FINISHED:
                final = lst
                unseen_final += 1
            # What the planner said before the snapshot must agree with its list.
            pre = self.task_states_pre.get(tid)
            if pre and lst is not None and pre[-1] in FINISHED and lst != pre[-1]:
                mismatches += 1
            if pre and listed is not None and lst is None and pre[-1] in FINISHED:
                finished_unlisted += 1
            if final == TaskStatus.DELIVERED:
                delivered.add(tid)
            elif final == TaskStatus.FAILED:
                failed.add(tid)
            elif final == TaskStatus.CANCELLED:
                cancelled.add(tid)
            elif lst is not None:
                opened.add(tid)
            elif listed is not None:
                lost.add(tid)
        all_seen = set(self.task_states) | (set(listed) if listed else set())
        unacked = [tid for tid, t in self.sent.items() if tid not in all_seen and t < t_end - 5.0]
        reasons = {}
        for tid in failed:
            r = self.fail_reasons.get(tid, "(reason not seen)")
            reasons[r] = reasons.get(r, 0) + 1
        # Planner stats.
        st0, st1 = self.stats_first, self.stats_last
        mem = [kb for _t, kb in self.mem_samples]
        slope = None
        if self.mem_samples and wall > 0:
            after = [(t - self.t_first, kb / 1024.0) for t, kb in self.mem_samples
                     if self.t_first and t - self.t_first >= 0.5 * wall]
            s = linear_slope(after)
            slope = s * 3600.0 if s is not None else None

        def mb(kb):
            return round(kb / 1024.0, 2) if kb is not None else None

        failures = []
        if self.collisions:
            failures.append("%d vertex collisions" % self.collisions)
        if self.swaps:
            failures.append("%d swaps" % self.swaps)
        if self.jumps:
            failures.append("%d jumps" % self.jumps)
        if self.offline_moves:
            failures.append("%d offline moves" % self.offline_moves)
        if lost:
            failures.append("%d lost tasks" % len(lost))
        if unacked:
            failures.append("%d unacknowledged tasks" % len(unacked))
        if listed is None:
            failures.append(list_error)
        if reason.startswith("STALL"):
            failures.append(reason)
        if not self.ticks:
            failures.append("no step commands")
        return {
            "pass": not failures,
            "failures": failures,
            "stop_reason": reason,
            "parameters": {
                "robot_steps_target": self.robot_steps_target,
                "duration_limit_s": self.duration,
                "planner_node": self.planner_node,
                "planner": self.params_of(self.planner_node),
                "fleet_sim": self.params_of(self.fleet_sim_node),
                "task_generator": self.params_of(self.task_generator_node),
            },
            "robots": self.max_robots,
            "ticks": self.ticks,
            "tick_first": self.first_tick,
            "tick_last": self.last_tick,
            "ticks_not_published": self.tick_gaps,
            "robot_steps": self.robot_steps,
            "wall_time_s": round(wall, 3),
            "robot_steps_per_s": round(self.robot_steps / wall, 2) if wall > 0 else None,
            "tasks": {
                "sent_seen_on_tasks_topic": len(self.sent),
                "accepted": len(accepted),
                "delivered": len(delivered),
                "failed": len(failed),
                "failed_reasons": reasons,
                "cancelled": len(cancelled),
                "open": len(opened),
                "lost": len(lost),
                "lost_ids": sorted(lost)[:50],
                "rejected": len(rejected),
                "first_seen_after_snapshot": len(self.late_tasks),
                "open_at_start": len(baseline_open),
                "listed_at_start": len(self.baseline or {}),
                "unacknowledged": len(unacked),
                "unacknowledged_ids": sorted(unacked)[:50],
                "final_state_only_from_list_tasks": unseen_final,
                "status_vs_list_tasks_mismatches": mismatches,
                "finished_not_in_list_tasks": finished_unlisted,
                "status_after_finished": self.status_after_finish,
                "max_open_in_planner_stats": self.max_tasks_open,
                "robots_busy_mean": round(sum(self.busy) / float(len(self.busy)), 1) if self.busy else None,
                "robots_busy_median": pct(self.busy, 50) if self.busy else None,
                "delivered_per_robot_step": (round(len(delivered) / float(self.robot_steps), 6)
                                             if self.robot_steps else None),
            },
            "safety": {
                "state_messages": self.state_msgs,
                "state_message_seq_gaps": self.seq_gaps,
                "vertex_collisions": self.collisions,
                "swaps": self.swaps,
                "jumps": self.jumps,
                "offline_moves": self.offline_moves,
                "robots_not_reporting_max": self.absent_max,
                "robots_not_reporting_at_end": sorted(self.absent_now),
                "robots_reporting_again": self.reappeared,
            },
            "planner_stats": {
                "overruns": st1.overruns if st1 else None,
                "overruns_in_run": (st1.overruns - st0.overruns) if st1 else None,
                "skipped_ticks": st1.skipped_ticks if st1 else None,
                "skipped_ticks_in_run": (st1.skipped_ticks - st0.skipped_ticks) if st1 else None,
                "forced_waits_sum": self.forced_waits,
                "fallback_ticks": getattr(st1, "fallback_ticks", None) if st1 else None,
                "fallback_ticks_in_run": (st1.fallback_ticks - st0.fallback_ticks
                                          if st1 and hasattr(st1, "fallback_ticks") else None),
                "offline_robots_max": self.max_offline,
                "tick_callback_s": {"p50": pct(self.step_times, 50), "p90": pct(self.step_times, 90),
                                    "p99": pct(self.step_times, 99),
                                    "max": max(self.step_times) if self.step_times else None},
                "plan_time_s": {"p50": pct(self.plan_times, 50), "p99": pct(self.plan_times, 99),
                                "max": max(self.plan_times) if self.plan_times else None},
                "tasks_delivered_total": st1.tasks_delivered if st1 else None,
                "tasks_failed_total": st1.tasks_failed if st1 else None,
                "planner": st1.planner if st1 else None,
                "tick_period_s": st1.tick_period if st1 else None,
                "stats_json": st1.planner_stats_json if st1 else None,
            },
            "planner_diagnostics": self.planner_diag,
            "planner_diagnostics_warnings": self.planner_diag_messages,
            "fleet_sim_diagnostics": self.sim_diag,
            "memory": {
                "pid": self.pid,
                "rss_start_mb": mb(self.mem_start),
                "rss_end_mb": mb(mem[-1]) if mem else None,
                "rss_peak_sampled_mb": mb(max(mem)) if mem else None,
                "vm_hwm_mb": mb(hwm),
                "rss_growth_mb_per_hour": round(slope, 2) if slope is not None else None,
                "rss_warm_mb": mb(self.rss_at(self.warm)),
                "warm_s": self.warm,
                "planner_pids": list(self.pids),
                "planner_restarts": max(0, len(self.pids) - 1),
                "samples": len(mem),
                "error": self.mem_error,
            },
        }

    def print_summary(self, s):
        def f(v, fmt="%.4f"):
            return "n/a" if v is None or (isinstance(v, float) and math.isnan(v)) else fmt % v
        p = s["parameters"]
        pl, fs, tg = p["planner"], p["fleet_sim"], p["task_generator"]
        t, sa, ps, m = s["tasks"], s["safety"], s["planner_stats"], s["memory"]
        lines = ["", "=" * 30 + " soak_benchmark summary " + "=" * 30,
                 "stopped because    %s" % s["stop_reason"],
                 "planner            %s, map %s, tick_rate %s Hz, threads %s" % (
                     pl.get("planner"), pl.get("map"), pl.get("tick_rate"), pl.get("threads")),
                 "limits             robot_steps %d, duration %s s" % (p["robot_steps_target"],
                                                                      p["duration_limit_s"] or "none"),
                 "faults             %s" % ", ".join("%s=%s" % (k, v) for k, v in sorted(fs.items())
                                                    if any(k.startswith(x) for x in
                                                           ("delay", "stop", "silent", "slip", "fault"))),
                 "task generator     rate %s/s, max_open %s" % (tg.get("rate"), tg.get("max_open")),
                 "robots             %d" % s["robots"],
                 "ticks              %d (ticks %s..%s, %d not published)" % (
                     s["ticks"], s["tick_first"], s["tick_last"], s["ticks_not_published"]),
                 "robot-steps        %d (%s per s)" % (s["robot_steps"], f(s["robot_steps_per_s"], "%.1f")),
                 "wall time          %.1f s" % s["wall_time_s"],
                 "tasks              accepted %d, delivered %d, failed %d, cancelled %d, open %d, LOST %d, "
                 "rejected %d, unacknowledged %d" % (t["accepted"], t["delivered"], t["failed"], t["cancelled"],
                                                     t["open"], t["lost"], t["rejected"], t["unacknowledged"]),
                 "failed because     %s" % (json.dumps(t["failed_reasons"]) if t["failed_reasons"] else "-"),
                 "tasks at start     %d listed by the planner, %d of them open (counted as accepted)" % (
                     t["listed_at_start"], t["open_at_start"]),
                 "task bookkeeping   final state only from list_tasks %d, status/list mismatches %d, finished "
                 "but not listed %d, status after finished %d, first seen after the snapshot %d" % (
                     t["final_state_only_from_list_tasks"], t["status_vs_list_tasks_mismatches"],
                     t["finished_not_in_list_tasks"], t["status_after_finished"], t["first_seen_after_snapshot"]),
                 "safety             collisions %d, swaps %d, jumps %d, offline moves %d (%d state msgs, "
                 "%d seq gaps)" % (sa["vertex_collisions"], sa["swaps"], sa["jumps"], sa["offline_moves"],
                                   sa["state_messages"], sa["state_message_seq_gaps"]),
                 "not reporting      max %d robots at once, %d came back, at end %s" % (
                     sa["robots_not_reporting_max"], sa["robots_reporting_again"],
                     sa["robots_not_reporting_at_end"] or "-"),
                 "planner overruns   %s (in run %s), skipped ticks %s (in run %s), forced waits %d, "
                 "fallback ticks %s (in run %s), offline robots max %s" % (
                     ps["overruns"], ps["overruns_in_run"], ps["skipped_ticks"], ps["skipped_ticks_in_run"],
                     ps["forced_waits_sum"], ps["fallback_ticks"], ps["fallback_ticks_in_run"],
                     ps["offline_robots_max"]),
                 "tick callback      p50 %s  p90 %s  p99 %s  max %s s" % tuple(
                     f(ps["tick_callback_s"][k]) for k in ("p50", "p90", "p99", "max")),
                 "plan time          p50 %s  p99 %s  max %s s" % tuple(
                     f(ps["plan_time_s"][k]) for k in ("p50", "p99", "max")),
                 "memory (planner)   start %s MB, end %s MB, peak %s MB (VmHWM %s MB), growth %s MB/h (2nd half)%s" % (
                     f(m["rss_start_mb"], "%.1f"), f(m["rss_end_mb"], "%.1f"), f(m["rss_peak_sampled_mb"], "%.1f"),
                     f(m["vm_hwm_mb"], "%.1f"), f(m["rss_growth_mb_per_hour"], "%.1f"),
                     (" (" + m["error"] + ")") if m["error"] else "")]
        if s["ticks"] and ps["overruns"] is None:
            lines.append("WARNING            no planner_stats received (message type mismatch? see the log)")
        for k, v in sorted(s["planner_diagnostics"].items()):
            lines.append("planner diag       %s: %s" % (k, v))
        if s["planner_diagnostics_warnings"]:
            lines.append("planner diag warn  %s" % json.dumps(s["planner_diagnostics_warnings"]))
        for k, v in sorted(s["fleet_sim_diagnostics"].items()):
            lines.append("fleet_sim diag     %s: %s" % (k, v))
        lines.append("RESULT             %s" % ("PASS" if s["pass"] else "FAIL: " + "; ".join(s["failures"])))
        lines.append("=" * 84)
        print("\n".join(lines))
        sys.stdout.flush()


def main():
    rospy.init_node("soak_benchmark")
    code = Soak().run()
    rospy.signal_shutdown("soak finished")
    sys.exit(code)


if __name__ == "__main__":
    main()
