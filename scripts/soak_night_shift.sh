#!/usr/bin/env bash
# A night shift without a human (issue 25): the headless warehouse (soak.launch: planner node with
# GD-RHCR on warehouse-10-20-10-2-1 at 2 Hz, fleet_sim, a full-load task generator, and
# soak_benchmark.py watching every robot state and task) with the robots' interlock OFF, and
#   - random delays (p_delay 0.01 per tick, 1..20 ticks),
#   - fleet_sim's faults every 60 s (a stalled robot, one going offline with a load, a silent
#     robot, slips),
#   - the planner process SIGKILLed every KILL_PERIOD s and respawned (it restores its tasks
#     from its journal),
#   - one pause and resume of the whole fleet (at 20% of the run), and one emergency stop and
#     release (at 45%).
# Writes results/night_shift.json (OUT) and exits non-zero unless: 0 collisions, 0 swaps, 0 moves
# the interlock would have stopped, 0 lost tasks (every accepted task delivered or still open in
# the planner), 0 accepted tasks failed, the planner restarted as often as it was killed, the
# p99 tick callback under the plan deadline, and the planner's RSS at the end within 10% of its
# RSS after warm-up (WARM s), and the fleet delivering after every restart at half its rate
# before the first kill or more.
#   bash scripts/soak_night_shift.sh                       # ROBOTS=500 DURATION=3600 SEED=1
#   ROBOTS=300 DURATION=600 bash scripts/soak_night_shift.sh
# Environment: ROBOTS (500), DURATION (s, 3600), SEED (1), KILL_PERIOD (900 s; for runs shorter
# than two periods DURATION/3, so a short run still restarts twice), WARM (300 s, at most
# DURATION/4), OUT (results/night_shift.json). Installs and builds what it needs
# (scripts/ros_env.sh). Its own ROS master port: PORT (11713); give another one to run beside
# something else that uses 11713.
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
ROBOTS=${ROBOTS:-500}
DURATION=${DURATION:-3600}
SEED=${SEED:-1}
KILL_PERIOD=${KILL_PERIOD:-900}
if [ "$DURATION" -lt $((2 * KILL_PERIOD)) ]; then KILL_PERIOD=$((DURATION / 3)); fi
WARM=${WARM:-300}
if [ "$WARM" -gt $((DURATION / 4)) ]; then WARM=$((DURATION / 4)); fi
OUT=${OUT:-$top/results/night_shift.json}
for v in ROBOTS DURATION SEED KILL_PERIOD WARM; do
  if ! [[ "${!v}" =~ ^[0-9]+$ ]] || [ "${!v}" -le 0 ]; then
    echo "soak_night_shift: $v='${!v}' must be a positive whole number" >&2
    exit 2
  fi
done
# shellcheck source=ros_env.sh
source "$top/scripts/ros_env.sh"
PORT=${PORT:-11713}
if ! [[ "$PORT" =~ ^[0-9]+$ ]] || [ "$PORT" -lt 1024 ] || [ "$PORT" -gt 65535 ]; then
  echo "soak_night_shift: PORT='$PORT' must be a port number (1024-65535)" >&2
  exit 2
fi
export ROS_MASTER_URI=http://127.0.0.1:$PORT
mkdir -p "$(dirname "$OUT")"
run="$ROS_HOME/night_shift"
rm -rf "$run" && mkdir -p "$run"
soak_json="$run/soak.json"
echo "soak_night_shift: $ROBOTS robots, ${DURATION} s, seed $SEED, planner killed every ${KILL_PERIOD} s -> $OUT"

roslaunch -p "$PORT" gd_rhcr_planner soak.launch num_robots:="$ROBOTS" duration:="$DURATION" \
  robot_steps:=2000000000 seed:="$SEED" faults:=true fault_period:=60 p_delay:=0.01 max_delay_ticks:=20 \
  interlock:=false respawn:=true task_store:="$run/tasks.jsonl" warm:="$WARM" output:="$soak_json" \
  >"$run/launch.log" 2>&1 &
launch=$!
cleanup() { kill "$launch" 2>/dev/null || true; }
trap cleanup EXIT

# Calls a service until the planner answers (it may be restarting).
call() {
  for _ in $(seq 30); do
    if rosservice call "$@" >>"$run/operator.log" 2>&1; then return 0; fi
    sleep 1
  done
  echo "soak_night_shift: rosservice call $* failed for 30 s" >&2
  return 1
}
# An operator hold of 10 s: hold_fleet T WHAT SERVICE ON_ARGS OFF_ARGS (failed calls counted).
hold_fleet() {
  echo "soak_night_shift: $1 s: $2 for 10 s"
  call "$3" "$4" || operator_errors=$((operator_errors + 1))
  sleep 10
  call "$3" "$5" || operator_errors=$((operator_errors + 1))
}
# The planner node of this run only: a child of this run's roslaunch (other runs on other ports
# have planner nodes of the same name).
planner_pid() { pgrep -P "$launch" -f "gd_rhcr_planner_node .*__name:=gd_rhcr_planner" | head -1; }

# Wait for the first step of the fleet (the soak's clock starts there).
for _ in $(seq 60); do
  if timeout 5 rostopic echo -n 1 /step_commands/tick >/dev/null 2>&1; then break; fi
  kill -0 "$launch" 2>/dev/null || { tail -30 "$run/launch.log"; echo "soak_night_shift: launch died" >&2; exit 1; }
done
start=$(date +%s)
kills=0 paused=0 stopped=0 operator_errors=0 kill_times=
next_kill=$KILL_PERIOD
pause_at=$((DURATION * 20 / 100))
stop_at=$((DURATION * 45 / 100))
while kill -0 "$launch" 2>/dev/null; do
  t=$(( $(date +%s) - start ))
  if [ "$t" -ge "$next_kill" ] && [ "$t" -lt "$DURATION" ]; then
    pid=$(planner_pid)
    if [ -n "$pid" ]; then
      kill -9 "$pid" && kills=$((kills + 1)) && kill_times="$kill_times $t" && echo "soak_night_shift: ${t} s: planner $pid SIGKILLed"
    fi
    next_kill=$((next_kill + KILL_PERIOD))
  fi
  if [ "$paused" = 0 ] && [ "$t" -ge "$pause_at" ]; then
    paused=1
    hold_fleet "$t" "fleet paused" /set_paused "{robot_id: -1, paused: true}" "{robot_id: -1, paused: false}"
  fi
  if [ "$stopped" = 0 ] && [ "$t" -ge "$stop_at" ]; then
    stopped=1
    hold_fleet "$t" "emergency stop" /emergency_stop "engage: true" "engage: false"
  fi
  sleep 2
done
trap - EXIT
if [ ! -s "$soak_json" ]; then
  tail -40 "$run/launch.log"
  echo "soak_night_shift: no soak summary ($soak_json)" >&2
  exit 1
fi

python3 - "$soak_json" "$OUT" "$ROBOTS" "$DURATION" "$SEED" "$kills" "$KILL_PERIOD" "$operator_errors" \
  "$(git -C "$top" rev-parse --short HEAD 2>/dev/null || echo unknown)" "$kill_times" "$run/launch.log" <<'PY'
import json, re, sys
soak_path, out, robots, duration, seed, kills, kill_period, operator_errors, commit, kill_times, log = sys.argv[1:]
s = json.load(open(soak_path))
t, sa, ps, m = s["tasks"], s["safety"], s["planner_stats"], s["memory"]
sim, pd = s["fleet_sim_diagnostics"], s["planner_diagnostics"]
def num(d, k):
    try:
        return float(d.get(k))
    except (TypeError, ValueError):
        return None
r = {
    "robots": int(robots), "duration_s": int(duration), "seed": int(seed), "commit": commit,
    # the same events seen by two observers: the soak (reported cells) and fleet_sim (physical)
    "collisions": max(sa["vertex_collisions"], int(num(sim, "collisions") or 0)),
    "swaps": max(sa["swaps"], int(num(sim, "swaps") or 0)),
    "jumps": sa["jumps"], "interlock_would_act": int(num(sim, "interlock would act") or 0),
    "accepted": t["accepted"], "delivered": t["delivered"], "open": t["open"], "failed": t["failed"],
    "lost_tasks": t["lost"] + t["unacknowledged"], "planner_kills": int(kills), "kill_period_s": int(kill_period),
    "planner_restarts": m.get("planner_restarts"), "operator_errors": int(operator_errors),
    "tick_p99_s": ps["tick_callback_s"]["p99"], "plan_deadline_s": num(pd, "plan deadline (s)") or
    (float(s["parameters"]["planner"].get("plan_deadline") or 0) or 0.7 / float(s["parameters"]["planner"]["tick_rate"])),
    "planner_rss_mb_warm": m.get("rss_warm_mb"), "planner_rss_mb_end": m.get("rss_end_mb"), "warm_s": m.get("warm_s"),
    "throughput_per_tick": (t["delivered"] / float(s["ticks"])) if s["ticks"] else None,
    "soak": s,
}
# Deliveries per second before the first kill and after each restart (from 60 s after the kill to
# the next kill or the end), from the soak's progress lines: a respawned planner must get the
# fleet going again, not only come back.
progress = [(float(a), int(b)) for a, b in re.findall(r"soak: (\d+) s, \d+ ticks, \d+ robot-steps, (\d+) tasks delivered",
                                                      open(log).read())]
def rate(lo, hi):
    pts = [p for p in progress if lo <= p[0] <= hi]
    return (pts[-1][1] - pts[0][1]) / (pts[-1][0] - pts[0][0]) if len(pts) >= 2 and pts[-1][0] > pts[0][0] else None
kt = [float(k) for k in kill_times.split()]
bounds = kt + [float(duration)]
r["deliveries_per_s"] = {"before_first_kill": rate(bounds[0] / 2, bounds[0]),
                         "after_restarts": [rate(k + 60, nxt) for k, nxt in zip(kt, bounds[1:])]}
checks = [
    ("collisions", r["collisions"] == 0), ("swaps", r["swaps"] == 0), ("jumps", r["jumps"] == 0),
    ("interlock acts", r["interlock_would_act"] == 0), ("lost tasks", r["lost_tasks"] == 0),
    ("failed accepted tasks", r["failed"] == 0), ("operator calls", r["operator_errors"] == 0),
    ("planner restarted after every kill", r["planner_restarts"] is not None and r["planner_restarts"] >= r["planner_kills"] > 0),
    ("p99 tick under the plan deadline", r["tick_p99_s"] is not None and r["plan_deadline_s"] is not None
     and r["tick_p99_s"] <= r["plan_deadline_s"]),
    ("RSS flat after warm-up (10%)", r["planner_rss_mb_warm"] and r["planner_rss_mb_end"]
     and r["planner_rss_mb_end"] <= 1.1 * r["planner_rss_mb_warm"]),
    ("deliveries after every restart (at least half the rate before the first kill)",
     r["deliveries_per_s"]["before_first_kill"] and all(
         x is not None and x >= 0.5 * r["deliveries_per_s"]["before_first_kill"] for x in r["deliveries_per_s"]["after_restarts"])),
    ("soak's own checks", s["pass"]),
]
r["failures"] = [name for name, ok in checks if not ok]
r["pass"] = not r["failures"]
json.dump(r, open(out, "w"), indent=2, sort_keys=True)
keys = ["robots", "duration_s", "collisions", "swaps", "interlock_would_act", "accepted", "delivered", "open",
        "failed", "lost_tasks", "planner_kills", "planner_restarts", "tick_p99_s", "plan_deadline_s",
        "planner_rss_mb_warm", "planner_rss_mb_end", "throughput_per_tick"]
for k in keys:
    print("%-22s %s" % (k, r[k]))
print("RESULT                 %s" % ("PASS" if r["pass"] else "FAIL: " + ", ".join(r["failures"])))
print("written to %s" % out)
sys.exit(0 if r["pass"] else 1)
PY
