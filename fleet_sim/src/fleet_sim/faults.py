"""Fault schedules and the slip rule of the simulated fleet (pure Python, no ROS).

A FaultSchedule is one kind of injected fault (delay, stop, silence, slip). Its occurrence k
becomes due at `start + k * period` seconds after the first step command (only k = 0 when
period <= 0) and hits robot `(robot + k * stride) % num_robots`, so periodic faults move from
robot to robot. An occurrence opens an Episode at its due time, or, when the schedule has a
readiness condition (e.g. "the robot carries a task"), at the first update at or after the due
time at which the condition holds; a periodic occurrence whose condition never held before the
next one fell due is skipped (`missed`). An episode lasts `duration` seconds (< 0: for good) or,
for slips, `count` commanded moves.
"""
import math
import random

# 4-neighbour directions in the order the slip rule tries them: +x, +y (down a row), -x, -y.
DIRECTIONS = ((1, 0), (0, 1), (-1, 0), (0, -1))


class Episode(object):
    __slots__ = ("robot", "k", "start", "until", "left", "info")

    def __init__(self, robot, k, start, until, left=0, info=None):
        self.robot = robot
        self.k = k
        self.start = start
        self.until = until
        self.left = left  # slips still to come (slip schedules)
        self.info = info  # what the readiness condition returned (e.g. the task id)

    def active(self, t):
        return self.start <= t < self.until


class FaultSchedule(object):
    def __init__(self, name, robot, start, duration, num_robots, period=0.0, stride=1, count=0,
                 ready=None):
        """robot < 0 disables the schedule. ready(robot_id) -> None when not ready, else a value
        stored in Episode.info (use True when there is nothing to record)."""
        self.name = name
        self.robot = robot
        self.start = float(start)
        self.duration = float(duration)
        self.n = num_robots
        self.period = float(period)
        self.stride = stride
        self.count = count
        self.ready = ready
        self.k = 0  # next occurrence to open
        self.fired = 0
        self.missed = 0
        self.last = None  # the last episode opened
        self.episodes = []  # episodes that may still be active

    @property
    def enabled(self):
        return self.robot >= 0

    def robot_of(self, k):
        return (self.robot + k * self.stride) % self.n

    def due(self, k):
        return self.start + k * self.period

    def update(self, t):
        """Opens the occurrences due by t (seconds after the first command; None = not yet).
        Returns the episodes opened."""
        opened = []
        if not self.enabled or t is None:
            return opened
        while not (self.period <= 0 and self.k > 0) and t >= self.due(self.k):
            rid = self.robot_of(self.k)
            if self.period > 0 and t >= self.due(self.k + 1):
                self.missed += 1  # its moment never came before the next one fell due
                self.k += 1
                continue
            if self.ready is None:
                info, begin = True, self.due(self.k)
            else:
                info, begin = self.ready(rid), t
                if info is None:
                    break
            until = begin + self.duration if self.duration >= 0 else math.inf
            ep = Episode(rid, self.k, begin, until, left=self.count, info=info)
            self.episodes.append(ep)
            opened.append(ep)
            self.last = ep
            self.fired += 1
            self.k += 1
        if self.count > 0:
            self.episodes = [e for e in self.episodes if e.left > 0]
        else:
            self.episodes = [e for e in self.episodes if e.until > t]
        return opened

    def active(self, rid, t):
        """True while an episode of this schedule holds robot rid at time t."""
        if t is None:
            return False
        return any(e.robot == rid and e.active(t) for e in self.episodes)

    def pending_slip(self, rid, t):
        """The slip episode with slips left for robot rid at time t, or None."""
        if t is None:
            return None
        for e in self.episodes:
            if e.robot == rid and e.left > 0 and e.start <= t:
                return e
        return None


def slip_target(cell, target, is_free, claimed):
    """Where a robot commanded from `cell` to the adjacent `target` ends when it slips.

    A 4-neighbour of `cell` that is free (is_free(x, y)) and not in `claimed` (cells occupied,
    commanded or being entered by any robot): first the two perpendicular to the commanded
    direction, then the reverse, in DIRECTIONS order; None when there is none (the robot stays
    in `cell`: it fails to move). Never two cells of motion, so never a jump, and never a cell
    any other robot holds or will enter, so never a collision.
    """
    d = (target[0] - cell[0], target[1] - cell[1])
    reverse = (-d[0], -d[1])
    order = [v for v in DIRECTIONS if v != d and v != reverse] + [reverse]
    for dx, dy in order:
        c = (cell[0] + dx, cell[1] + dy)
        if is_free(*c) and c not in claimed:
            return c
    return None


class RandomDelays(object):
    """Random delays as in the League of Robot Runners 2026: on every tick a robot that is not
    delayed starts a delay with probability `p`, lasting a uniform 1..`max_ticks` tick periods.
    Robots are objects with `delay_until` (s), `moving`, `turning` (optional) and `duration` (s,
    of the move or turn under way):
    a robot at rest stays put until `delay_until`; a moving robot stops where it is and arrives
    that much later (its `duration` grows by the delay). Seeded, so a seed fixes the pattern."""

    def __init__(self, p, max_ticks, seed):
        if not 0.0 <= p <= 1.0 or max_ticks < 1:
            raise ValueError("p_delay must be in [0, 1] and max_delay_ticks >= 1")
        self.p = p
        self.max_ticks = max_ticks
        self.rng = random.Random(seed)
        self.started = 0

    def tick(self, now, period, robots):
        """One tick at time `now` (s) with tick period `period` (s). Returns the delays started."""
        n = 0
        if self.p <= 0:
            return n
        for r in robots:
            if now < r.delay_until or self.rng.random() >= self.p:
                continue
            length = self.rng.randint(1, self.max_ticks) * period
            r.delay_until = now + length
            if r.moving or getattr(r, "turning", False):  # a turn under way is stopped too
                r.duration += length
            n += 1
        self.started += n
        return n
