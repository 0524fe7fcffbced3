#!/usr/bin/env python3
"""Simulated warehouse robots for gd_rhcr.

Waits for the latched `map` (nav_msgs/OccupancyGrid), places ~num_robots robots on distinct
free cells (seeded), and executes `step_commands` (every robot, each tick) and
`step_command_updates` (between ticks, the robots just given a move): each robot keeps its last
command and, whenever it is at rest and free to move (not delayed, stalled or offline), moves to
the commanded cell, taking ~move_fraction of the tick period, and switches its reported cell on
arrival. Robots
publish `robot_states` (gd_rhcr_msgs/RobotStateArray) and tf map -> <~tf_prefix>robot_N/base_link
with a smoothly interpolated pose (~tf_prefix, default empty: e.g. "fleet_a/" keeps two fleets'
robot frames apart). Like a real robot's safety stop (the interlock), a robot never starts
a move into a cell held by a robot that is not leaving it, or that a robot still moving is
entering (counted as `blocked moves` on /diagnostics; zero when the planner's commands are
followed by everyone).

Turning robots (issue 23): every robot has a heading (east, south, west, north; RobotState.heading,
  the tf yaw follows it) and moves only forward, in the direction it faces.
  ~turn_time t (default 1): ticks (tick periods, times the robot's speed factor) a quarter turn
      in place takes; 0 = robots turn instantly (the move's direction is taken at once, as robots
      that need not turn). A robot at rest whose command names a neighbour it does not face turns
      towards it first (quarter turn by quarter turn, in its cell), then moves; one whose command
      names its own cell and a heading (StepCommand.next_heading) turns to it. A quarter turn
      under way is finished; the reported heading switches when it is. Start headings are
      seeded (~seed).

Realistic execution (issue 13):
  ~speed_spread s (default 0): each robot's move takes move_fraction * tick_period * f, with f
      drawn per robot uniformly from [1 - s, 1 + s] (seeded), so robots run at different speeds.
  ~p_delay p, ~max_delay_ticks D (defaults 0, 20): random delays as in the League of Robot
      Runners 2026: on every tick (step command) a robot not already delayed starts a delay with
      probability p, lasting a uniform 1..D tick periods; a robot at rest ignores commands while
      delayed, a robot in motion stops where it is and arrives that much later. Seeded.
  ~absent_robots (list of ids, default []): robots that are not on the floor (switched off, not
      delivered yet): they never report, hold no cell and ignore commands; the planner must run
      the rest of the fleet without them.
  ~interlock (default true): false = robots start every commanded move at once, as a robot
      without a safety stop would; every move the interlock would have stopped is still counted
      (`interlock would act`), as are the resulting collisions (`collisions`: a robot arrives in a
      cell another robot is in; `swaps`: two robots start moves into each other's cells).

Fault injection (for tests, demos and soak runs); times in seconds after the first step
command; robot ids < 0 (the defaults) disable a fault:
  ~delay_robot N, ~delay_start S, ~delay_duration D: robot N ignores commands (stalls) for D s
      from S s.
  ~stop_robot N, ~stop_at S, ~stop_duration D: robot N goes offline (mode OFFLINE, does not
      move; a move under way is finished) at S s, for D s (D < 0: for good).
  ~stop_mid_task (bool, default false): the stop fires at the first moment >= S at which robot N
      carries a task (the task_id of its last command >= 0) instead of exactly at S, and lasts
      D s from then. Diagnostics: "stops fired", "stop fired at" (s after the first command),
      "stopped robot", "stopped robot task" (the task it held), "stops missed".
  ~silent_robot N, ~silent_at S, ~silent_duration D (D < 0: for good): robot N dies: from the
      first moment >= S at which it is at rest and was last reported at rest (so its last report
      is where it is), it is left out of robot_states and tf, ignores commands and does not move,
      for D s. Then it reports again at its cell, with the mode and task of the last command it
      took before it died. Diagnostics: "silences", "silent robot", "silent at", "silent now".
  ~slip_robot N, ~slip_at S, ~slip_count K (default 1): from S s, the next K moves robot N
      starts end in another cell than commanded: a free 4-neighbour of its source cell that no
      robot occupies, is commanded into or is entering (first the two perpendicular to the
      commanded direction, then the reverse), or, if there is none, its source cell (it fails to
      move). Never a jump or a collision. Diagnostics: "slips", "slips that stayed".
  ~fault_period P (default 0 = each fault once): when > 0, every fault above repeats every P s
      (occurrence k at S + k*P) on robot (N + k*~fault_stride) % num_robots (~fault_stride
      default 7), so the faults visit different robots; durations must then be >= 0. Choose
      base robots that differ by neither 0 nor +-stride so two faults never share a robot.
      A stop_mid_task or silent occurrence whose moment did not come before the next one fell
      due is skipped ("stops missed", "silences missed").
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
from fleet_sim.faults import FaultSchedule, RandomDelays, slip_target
from fleet_sim.grid_frame import GridFrame, adjacent_or_same, resolve_moves, tick_entry_taken


def yaw_quaternion(yaw):
    return (0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0))


# Headings as the planner numbers them (east, south, west, north; RobotState.HEADING_* - 1) and
# their cell steps: south is +row in cells, -y in the map frame, so a heading's yaw is -h * pi/2.
HEADING_STEPS = ((1, 0), (0, 1), (-1, 0), (0, -1))


def heading_yaw(h):
    return (0.0, -math.pi / 2.0, math.pi, math.pi / 2.0)[h]


def heading_of_move(src, dst):
    return HEADING_STEPS.index((dst[0] - src[0], dst[1] - src[1]))


def quarter_turn(h, target):
    """+1 (clockwise) or -1 (counter-clockwise): the first quarter turn from h towards target
    (a half turn starts clockwise)."""
    return -1 if (target - h) % 4 == 3 else 1


class Robot(object):
    def __init__(self, rid, cell):
        self.id = rid
        self.cell = cell
        self.src = cell
        self.dst = cell
        self.t0 = 0.0
        self.duration = 0.0
        self.moving = False
        self.heading = 0  # east, south, west, north = 0..3
        self.turning = 0  # +1 / -1 while a quarter turn clockwise / counter-clockwise is under way
        self.mode = RobotState.MODE_IDLE
        self.task_id = -1
        self.reported = None  # (cell, moving) of the last published state
        self.speed = 1.0  # move time factor (~speed_spread)
        self.delay_until = 0.0  # a random delay (~p_delay) holds the robot until then
        self.cmd = None  # the cell of its last command: at rest, it starts the move when it can
        self.cmd_heading = None  # the heading of its last command (None: any)
        self.update_tick = -1  # the tick of the last step_command_updates entry for it
        self.blocked_on = None  # the (cell, target) move the interlock stopped (counted once)


class FleetSim(object):
    def __init__(self):
        self.n = rospy.get_param("~num_robots", 10)
        self.seed = rospy.get_param("~seed", 1)
        self.move_fraction = rospy.get_param("~move_fraction", 0.6)
        self.rate = rospy.get_param("~publish_rate", 20.0)
        self.speed_spread = float(rospy.get_param("~speed_spread", 0.0))
        self.p_delay = float(rospy.get_param("~p_delay", 0.0))
        self.max_delay_ticks = int(rospy.get_param("~max_delay_ticks", 20))
        self.interlock = bool(rospy.get_param("~interlock", True))
        self.turn_time = float(rospy.get_param("~turn_time", 1.0))
        if not self.turn_time >= 0.0:
            rospy.logfatal("fleet_sim: ~turn_time must be >= 0 ticks per quarter turn, not %s", self.turn_time)
            sys.exit(1)
        if not 0.0 <= self.speed_spread < 1.0:
            rospy.logfatal("fleet_sim: ~speed_spread must be in [0, 1), not %s", self.speed_spread)
            sys.exit(1)
        try:
            self.delays = RandomDelays(self.p_delay, self.max_delay_ticks, int(rospy.get_param("~seed", 1)) * 7919 + 13)
        except ValueError as e:
            rospy.logfatal("fleet_sim: %s", e)
            sys.exit(1)
        self.interlock_would_act = 0
        self.collisions = 0
        self.swaps = 0
        self.delays_started = 0
        self.tf_enabled = rospy.get_param("~publish_tf", True)
        self.frame = rospy.get_param("~frame_id", "map")
        self.tf_prefix = str(rospy.get_param("~tf_prefix", ""))
        if self.tf_prefix and not self.tf_prefix.endswith("/"):
            self.tf_prefix += "/"
        self.lock = threading.Lock()
        self.grid = None
        self.robots = []
        self.first_command = None
        self.blocked_moves = 0
        self.invalid_commands = 0
        self.commands_received = 0
        self.last_tick = 0
        self.tick_period = 0.5  # of the last command
        self.slips = 0
        self.slips_stayed = 0
        self.load_faults()

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
        absent = rospy.get_param("~absent_robots", [])
        if not isinstance(absent, list) or any(not isinstance(a, int) or not 0 <= a < self.n for a in absent):
            rospy.logfatal("fleet_sim: ~absent_robots must be a list of robot ids 0..%d", self.n - 1)
            sys.exit(1)
        self.absent = set(absent)
        for a in self.absent:  # off the map, so it never meets a cell of the floor
            r = self.robots[a]
            r.cell = r.src = r.dst = (-1000 - a, -1000)
        speed_rng = random.Random(self.seed * 104729 + 1)
        for r in self.robots:
            r.speed = speed_rng.uniform(1.0 - self.speed_spread, 1.0 + self.speed_spread)
        heading_rng = random.Random(self.seed * 15485863 + 5)
        for r in self.robots:
            r.heading = heading_rng.randrange(4)
        self.turns = 0
        self.turns_before_moves = 0  # turns a command to a neighbour not faced made (none in rotation)
        rospy.loginfo("fleet_sim: %d robots on a %dx%d map", self.n, self.grid.width, self.grid.height)

        self.state_pub = rospy.Publisher("robot_states", RobotStateArray, queue_size=10)
        self.diag_pub = rospy.Publisher("/diagnostics", DiagnosticArray, queue_size=10)
        self.tf_pub = tf2_ros.TransformBroadcaster() if self.tf_enabled else None
        rospy.Subscriber("step_commands", StepCommandArray, self.on_commands, queue_size=10)
        # Between ticks the manager sends the moves that became free on step_command_updates.
        rospy.Subscriber("step_command_updates", StepCommandArray, self.on_updates, queue_size=100)
        rospy.Timer(rospy.Duration(1.0 / self.rate), self.on_timer)
        rospy.Timer(rospy.Duration(1.0), self.on_diagnostics)

    # --- faults -----------------------------------------------------------------------------
    def load_faults(self):
        period = float(rospy.get_param("~fault_period", 0.0))
        stride = int(rospy.get_param("~fault_stride", 7))
        self.fault_period = period

        def schedule(name, robot_param, start_param, start_default, duration_param, duration_default,
                     count=0, ready=None):
            robot = int(rospy.get_param(robot_param, -1))
            start = float(rospy.get_param(start_param, start_default))
            duration = float(rospy.get_param(duration_param, duration_default)) if duration_param else -1.0
            if robot >= self.n:
                rospy.logfatal("fleet_sim: %s %d is not a robot (0..%d)", robot_param, robot, self.n - 1)
                sys.exit(1)
            if robot >= 0 and period > 0 and duration_param and duration < 0:
                rospy.logfatal("fleet_sim: with ~fault_period > 0, %s must be >= 0 (a fault for good "
                               "would repeat until no robot is left)", duration_param)
                sys.exit(1)
            if robot >= 0:
                rospy.loginfo("fleet_sim: fault %s on robot %d at %.1f s%s%s", name, robot, start,
                              " for %.1f s" % duration if duration >= 0 and duration_param else "",
                              ", every %.1f s on robot +%d" % (period, stride) if period > 0 else "")
            return FaultSchedule(name, robot, start, duration, self.n, period=period, stride=stride,
                                 count=count, ready=ready)

        self.stop_mid_task = bool(rospy.get_param("~stop_mid_task", False))
        self.delay = schedule("delay", "~delay_robot", "~delay_start", 5.0, "~delay_duration", 3.0)
        self.stop = schedule("stop", "~stop_robot", "~stop_at", 5.0, "~stop_duration", -1.0,
                             ready=self.carries_task if self.stop_mid_task else None)
        self.silent = schedule("silent", "~silent_robot", "~silent_at", 10.0, "~silent_duration", -1.0,
                               ready=self.at_rest_and_reported)
        slip_count = int(rospy.get_param("~slip_count", 1))
        self.slip = schedule("slip", "~slip_robot", "~slip_at", 10.0, None, None,
                             count=max(1, slip_count))

    # Readiness conditions (with self.lock held). None = not yet.
    def carries_task(self, rid):
        r = self.robots[rid]
        return r.task_id if r.task_id >= 0 else None

    def at_rest_and_reported(self, rid):
        r = self.robots[rid]
        return True if (not r.moving and r.reported == (r.cell, False)) else None

    def elapsed(self, now):
        return None if self.first_command is None else now - self.first_command

    def update_faults(self, now):
        e = self.elapsed(now)
        for f in (self.delay, self.stop, self.silent, self.slip):
            for ep in f.update(e):
                if f is self.stop and self.stop_mid_task:
                    rospy.logwarn("fleet_sim: robot %d goes offline at %.2f s holding task %d",
                                  ep.robot, ep.start, ep.info)
                else:
                    rospy.logwarn("fleet_sim: fault %s on robot %d at %.2f s", f.name, ep.robot, ep.start)
        return e

    def stalled(self, rid, now):
        return self.delay.active(rid, self.elapsed(now))

    def offline(self, rid, now):
        return self.stop.active(rid, self.elapsed(now))

    def dead(self, rid, now):
        return self.silent.active(rid, self.elapsed(now))

    # --- motion -----------------------------------------------------------------------------
    def advance(self, now):
        for r in self.robots:  # quarter turns done (a turn keeps the robot in its cell)
            if r.turning and now >= r.t0 + r.duration:
                r.heading = (r.heading + r.turning) % 4
                r.turning = 0
        arriving = [r for r in self.robots if r.moving and now >= r.t0 + r.duration]
        if not arriving:
            return
        occupied = {}
        for o in self.robots:
            occupied[o.cell] = occupied.get(o.cell, 0) + 1
        # In the order they arrive; robots arriving at the same moment first all leave their
        # cells (a robot that follows another at the same speed is not counted as a collision).
        arriving.sort(key=lambda a: a.t0 + a.duration)
        i = 0
        while i < len(arriving):
            j = i
            while j < len(arriving) and arriving[j].t0 + arriving[j].duration <= arriving[i].t0 + arriving[i].duration + 1e-9:
                j += 1
            group = arriving[i:j]
            for r in group:
                occupied[r.cell] -= 1
            for r in group:
                if occupied.get(r.dst, 0) > 0:
                    self.collisions += 1
                    rospy.logerr_throttle(1.0, "fleet_sim: robot %d arrived in %s, where another robot is" %
                                          (r.id, r.dst))
                occupied[r.dst] = occupied.get(r.dst, 0) + 1
                r.cell = r.dst
                r.src = r.dst
                r.moving = False
            i = j

    def start_delays(self, now, period):
        self.delays_started += self.delays.tick(now, period, [r for r in self.robots if r.id not in self.absent])

    def delayed(self, rid, now):
        return now < self.robots[rid].delay_until
    def on_commands(self, msg):
        """A tick's step commands: every robot's command. Random delays start here."""
        self.take_commands(msg, tick=True)

    def on_updates(self, msg):
        """Between ticks: the commands of the robots given a new move (the others keep theirs)."""
        self.take_commands(msg, tick=False)

    def take_commands(self, msg, tick):
        now = rospy.get_time()
        with self.lock:
            if self.first_command is None:
                self.first_command = now
            self.commands_received += 1
            if tick:
                self.last_tick = msg.tick
            self.tick_period = msg.tick_period
            self.advance(now)
            e = self.update_faults(now)
            if tick:
                self.start_delays(now, msg.tick_period)
            for c in msg.commands:
                if c.robot_id >= self.n:
                    self.invalid_commands += 1
                    continue
                r = self.robots[c.robot_id]
                if self.dead(r.id, now) or r.id in self.absent:
                    continue  # a dead or absent robot hears nothing
                # Updates carry the tick they follow (see tick_entry_taken).
                if tick and not tick_entry_taken(r.update_tick, msg.tick):
                    continue
                if tick and msg.tick < r.update_tick:
                    r.update_tick = -1  # the manager restarted: its ticks count from 1 again
                elif not tick:
                    r.update_tick = msg.tick
                target = (c.next_x, c.next_y)
                heading = c.next_heading - 1 if 1 <= c.next_heading <= 4 else None
                if not self.offline(r.id, now):
                    r.mode = c.mode
                    r.task_id = c.task_id
                if r.moving and target != r.dst:
                    self.invalid_commands += 1
                    rospy.logwarn_throttle(2.0, "fleet_sim: robot %d, moving to %s, ignores command to %s",
                                           r.id, r.dst, target)
                    continue
                if not r.moving and (not adjacent_or_same(r.cell, target) or not self.grid.is_free(*target)):
                    self.invalid_commands += 1
                    rospy.logwarn_throttle(2.0, "fleet_sim: robot %d ignores command to %s from %s",
                                           r.id, target, r.cell)
                    r.cmd = None  # keeps still
                    continue
                r.cmd = target
                r.cmd_heading = heading
            slips = self.slips
            self.start_moves(now, e)
            # A robot that has just slipped says so at once (where it is heading), as a driver
            # would, not only at the next report period.
            report = self.states(now) if self.slips != slips else None
        if report:
            self.publish_states(*report)

    def start_moves(self, now, e):
        """Robots at rest that can move (not delayed, stalled, offline, dead or absent) start their
        commanded move, unless the interlock (when on) stops it."""
        for r in self.robots:  # OFFLINE at rest cancels its move (the manager gives the cell away)
            if not r.moving and r.cmd is not None and self.offline(r.id, now):
                r.cmd = None
        frozen = [(r.moving or r.turning or self.stalled(r.id, now) or self.offline(r.id, now) or
                   self.dead(r.id, now) or self.delayed(r.id, now) or r.id in self.absent) for r in self.robots]
        pending = [r for r in self.robots if not r.moving and r.cmd is not None and r.cmd != r.cell and
                   not self.start_turn(r, now, frozen[r.id])]
        for r in self.robots:  # a command to stay with a heading: turn in place
            if not r.moving and r.cmd == r.cell and r.cmd_heading is not None:
                self.start_turn(r, now, frozen[r.id])
        if not pending:
            return
        cells = [r.cell for r in self.robots]
        targets = list(cells)
        for r in pending:
            targets[r.id] = r.cmd
        if all(frozen[r.id] for r in pending):
            return
        # A robot still moving holds the cell it enters as well.
        entering = [r.dst for r in self.robots if r.moving]
        moves, blocked = resolve_moves(cells, targets, frozen, entering)
        for i in blocked:  # each stopped move is counted once, not at every retry
            r = self.robots[i]
            if r.blocked_on != (r.cell, targets[i]):
                r.blocked_on = (r.cell, targets[i])
                self.interlock_would_act += 1
                if self.interlock:
                    self.blocked_moves += 1
        if not self.interlock:  # every commanded move starts; what the interlock would stop is counted
            moves = set(i for i in range(self.n) if not frozen[i] and targets[i] != cells[i])
        if self.slip.episodes:
            slipped = False
            for i in sorted(moves):
                ep = self.slip.pending_slip(i, e)
                if ep is None:
                    continue
                # Never a cell another robot holds, enters or was commanded into (also one turning
                # before it moves there, or delayed).
                claimed = set(cells) | set(targets) | set(entering) | set(o.cmd for o in self.robots if o.cmd is not None)
                alt = slip_target(cells[i], targets[i], self.grid.is_free, claimed)
                rospy.logwarn("fleet_sim: robot %d slips: commanded %s -> %s, goes to %s", i, cells[i],
                              targets[i], alt if alt else "nowhere (stays)")
                targets[i] = alt if alt else cells[i]
                self.robots[i].cmd = targets[i]  # the move it makes (or none): never retried
                ep.left -= 1
                self.slips += 1
                self.slips_stayed += alt is None
                slipped = True
            if slipped and self.interlock:  # a robot that stays now blocks the robots that were to follow it
                moves, _ = resolve_moves(cells, targets, frozen, entering)
        duration = max(0.01, self.move_fraction * self.tick_period)
        moving_pairs = set((o.src, o.dst) for o in self.robots if o.moving)
        for i in moves:
            r = self.robots[i]
            if targets[i] == r.cell:
                continue  # slipped and stayed
            if (targets[i], r.cell) in moving_pairs:  # two robots moving into each other's cells
                self.swaps += 1
            moving_pairs.add((r.cell, targets[i]))
            r.src, r.dst = r.cell, targets[i]
            r.t0, r.duration, r.moving = now, max(0.01, duration * r.speed), True
            r.blocked_on = None
            r.heading = heading_of_move(r.src, r.dst)  # faces it (turned first, or instantly)

    def start_turn(self, r, now, frozen):
        """Robot r at rest turns towards its command's heading (a move's direction, else the
        commanded heading) unless it faces it: a quarter turn of ~turn_time ticks starts (not when
        frozen or already turning), or with ~turn_time 0 it faces it at once. True while it must
        turn before it moves."""
        want = heading_of_move(r.cell, r.cmd) if r.cmd != r.cell else r.cmd_heading
        if want is None or want == r.heading:
            return False
        if self.turn_time <= 0:
            r.heading = want
            return False
        if not frozen and not r.turning:
            r.turning = quarter_turn(r.heading, want)
            r.t0, r.duration = now, max(0.01, self.turn_time * self.tick_period * r.speed)
            self.turns += 1
            self.turns_before_moves += r.cmd != r.cell
        return True

    def yaw_of(self, r, now):
        """The robot's yaw: its heading's, turning smoothly during a quarter turn."""
        yaw = heading_yaw(r.heading)
        if r.turning:
            s = min(1.0, max(0.0, (now - r.t0) / r.duration))
            yaw -= r.turning * (s * s * (3 - 2 * s)) * math.pi / 2.0
        return yaw

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
        with self.lock:
            self.advance(now)
            e = self.update_faults(now)
            if self.first_command is not None:
                self.start_moves(now, e)  # a robot whose delay or stall is over makes its move now
            arr, transforms = self.states(now)
        self.publish_states(arr, transforms)

    def publish_states(self, arr, transforms):
        self.state_pub.publish(arr)
        if transforms:
            self.tf_pub.sendTransform(transforms)

    def states(self, now):
        """Every reporting robot's state (and tf) at `now`; call with the lock held."""
        stamp = rospy.Time.now()
        arr = RobotStateArray()
        arr.header.stamp = stamp
        arr.header.frame_id = self.frame
        transforms = []
        for r in self.robots:
            if self.dead(r.id, now) or r.id in self.absent:
                continue
            s = RobotState()
            s.id = r.id
            s.x, s.y = r.cell
            px, py = self.pose_of(r, now)
            q = yaw_quaternion(self.yaw_of(r, now))
            s.pose = Pose()
            s.pose.position.x, s.pose.position.y = px, py
            s.pose.orientation.x, s.pose.orientation.y, s.pose.orientation.z, s.pose.orientation.w = q
            s.mode = RobotState.MODE_OFFLINE if self.offline(r.id, now) else r.mode
            s.task_id = r.task_id
            s.moving = r.moving
            s.heading = r.heading + 1  # RobotState.HEADING_*
            if r.moving:  # the cell it is entering, as a driver knows it (also when it slips)
                s.entering_known = True
                s.entering_x, s.entering_y = r.dst
            r.reported = (r.cell, r.moving)
            arr.robots.append(s)
            if self.tf_pub:
                t = TransformStamped()
                t.header.stamp = stamp
                t.header.frame_id = self.frame
                t.child_frame_id = "%srobot_%d/base_link" % (self.tf_prefix, r.id)
                t.transform.translation.x, t.transform.translation.y = px, py
                (t.transform.rotation.x, t.transform.rotation.y,
                 t.transform.rotation.z, t.transform.rotation.w) = q
                transforms.append(t)
        return arr, transforms

    def on_diagnostics(self, _event):
        now = rospy.get_time()
        with self.lock:
            e = self.elapsed(now)
            st = DiagnosticStatus()
            st.name = rospy.get_name() + ": fleet"
            st.hardware_id = "fleet_sim"
            st.level = DiagnosticStatus.OK if self.blocked_moves == 0 and self.interlock_would_act == 0 \
                else DiagnosticStatus.WARN
            if self.collisions or self.swaps:
                st.level = DiagnosticStatus.ERROR
            st.message = "%d robots" % self.n
            values = [("robots", self.n), ("commands received", self.commands_received),
                      ("last tick", self.last_tick), ("blocked moves", self.blocked_moves),
                      ("invalid commands", self.invalid_commands),
                      ("interlock", "on" if self.interlock else "off"),
                      ("interlock would act", self.interlock_would_act),
                      ("collisions", self.collisions), ("swaps", self.swaps),
                      ("turn time", self.turn_time), ("turns", self.turns),
                      ("turns before moves", self.turns_before_moves),
                      ("speed spread", self.speed_spread), ("p_delay", self.p_delay),
                      ("max delay ticks", self.max_delay_ticks), ("delays started", self.delays_started),
                      ("delayed now", sum(1 for r in self.robots if now < r.delay_until)),
                      ("absent robots", " ".join(str(a) for a in sorted(self.absent)))]
            if self.fault_period > 0:
                values.append(("fault period", self.fault_period))
            if self.delay.enabled:
                values += [("delays", self.delay.fired),
                           ("delayed robot", self.delay.last.robot if self.delay.last else -1)]
            if self.stop.enabled:
                last = self.stop.last
                values += [("stops fired", self.stop.fired), ("stops missed", self.stop.missed),
                           ("stopped robot", last.robot if last else -1),
                           ("stop fired at", "%.3f" % last.start if last else "")]
                if self.stop_mid_task:
                    values.append(("stopped robot task", last.info if last else -1))
                values.append(("offline now", " ".join(str(ep.robot) for ep in self.stop.episodes
                                                       if ep.active(e))))
            if self.silent.enabled:
                last = self.silent.last
                values += [("silences", self.silent.fired), ("silences missed", self.silent.missed),
                           ("silent robot", last.robot if last else -1),
                           ("silent at", "%.3f" % last.start if last else ""),
                           ("silent now", " ".join(str(ep.robot) for ep in self.silent.episodes
                                                   if ep.active(e)))]
            if self.slip.enabled:
                values += [("slips", self.slips), ("slips that stayed", self.slips_stayed),
                           ("slip robot", self.slip.last.robot if self.slip.last else -1)]
            for k, v in values:
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
