#!/usr/bin/env bash
# Turning robots in ROS (issue 23, item 5): the headless warehouse (soak.launch without faults:
# planner node with GD-RHCR on warehouse-10-20-10-2-1 at 2 Hz, fleet_sim with its interlock off, a
# full-load task generator) three times:
#   mapf-instant:   planning without turns, robots that turn instantly (fleet_sim turn_time 0);
#   rotation-turns: planning with turns (~action_model rotation), a tick per quarter turn;
#   mapf-turns:     planning without turns, robots that take a tick per quarter turn (they turn
#                   before each move into a cell they do not face; waiting, towards the next one).
# Prints throughput (deliveries per tick), collisions, swaps, interlock acts and turns, and writes
# results/turns.json; not a test.
#   bash scripts/bench_turns.sh                      # ROBOTS=200 DURATION=180
#   ROBOTS=50 DURATION=60 bash scripts/bench_turns.sh
# Environment: ROBOTS (200), DURATION (s per run, 180), TURN_TIME (1 tick per quarter turn),
# PLANNER (gd-rhcr), SEED (1), RUNS ("mapf-instant rotation-turns mapf-turns"), OUT
# (results/turns.json). Installs and builds what it needs (scripts/ros_env.sh; GDRHCR_SKIP_BUILD=1
# uses the workspace as it is). Holds /tmp/gdrhcr_ros.lock while it runs (one ROS run at a time).
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
ROBOTS=${ROBOTS:-200}
DURATION=${DURATION:-180}
TURN_TIME=${TURN_TIME:-1}
PLANNER=${PLANNER:-gd-rhcr}
SEED=${SEED:-1}
RUNS=${RUNS:-"mapf-instant rotation-turns mapf-turns"}
OUT=${OUT:-$top/results/turns.json}
# shellcheck source=ros_env.sh
source "$top/scripts/ros_env.sh"
export ROS_MASTER_URI=http://127.0.0.1:11714
mkdir -p "$top/results" "$ROS_HOME"
runs=()
for run in $RUNS; do
  case "$run" in
    mapf-instant) model=mapf turn=0 ;;
    rotation-turns) model=rotation turn=$TURN_TIME ;;
    mapf-turns) model=mapf turn=$TURN_TIME ;;
    *) echo "bench_turns: unknown run '$run' (mapf-instant, rotation-turns, mapf-turns)" >&2; exit 2 ;;
  esac
  out="$ROS_HOME/bench_turns_${run}.json"
  rm -f "$out"
  echo "bench_turns: $run (action_model $model, turn_time $turn), $ROBOTS robots, interlock off, ${DURATION}s -> $out"
  flock /tmp/gdrhcr_ros.lock roslaunch -p 11714 gd_rhcr_planner soak.launch faults:=false \
    num_robots:="$ROBOTS" planner:="$PLANNER" seed:="$SEED" duration:="$DURATION" robot_steps:=1000000000 \
    action_model:="$model" turn_time:="$turn" interlock:=false \
    output:="$out" >"$ROS_HOME/bench_turns_${run}.log" 2>&1 || true
  runs+=("$run" "$model" "$turn" "$out")
done
commit=$(git -C "$top" rev-parse --short HEAD 2>/dev/null || echo unknown)
/usr/bin/python3 - "$OUT" "$ROBOTS" "$DURATION" "$PLANNER" "$SEED" "$commit" "${runs[@]}" <<'PY'
import json, sys
out, robots, duration, planner, seed, commit = sys.argv[1:7]
rest = sys.argv[7:]
res = {"robots": int(robots), "duration_s": float(duration), "planner": planner, "seed": int(seed),
       "map": "warehouse-10-20-10-2-1", "tick_rate_hz": 2.0, "interlock": "off", "commit": commit,
       "command": "ROBOTS=%s DURATION=%s bash scripts/bench_turns.sh" % (robots, duration), "runs": {}}
print("\n%-15s %-9s %-5s %-6s %-10s %-11s %-6s %-6s %-9s %-7s %-6s" % (
    "run", "model", "turn", "ticks", "delivered", "throughput", "coll.", "swaps", "interlock", "turns", "lost"))
for i in range(0, len(rest), 4):
    run, model, turn, path = rest[i:i + 4]
    try:
        s = json.load(open(path))
    except (OSError, ValueError) as e:
        print("%-15s no result (%s)" % (run, e))
        continue
    d = s.get("fleet_sim_diagnostics", {})
    num = lambda k: int(float(d.get(k, 0)))
    ticks = max(1, s["ticks"])
    f = {"action_model": model, "turn_time": float(turn), "ticks": s["ticks"], "delivered": s["tasks"]["delivered"],
         "throughput": round(s["tasks"]["delivered"] / ticks, 4),
         "collisions": max(num("collisions"), s["safety"]["vertex_collisions"]),
         "swaps": max(num("swaps"), s["safety"]["swaps"]), "jumps": s["safety"]["jumps"],
         "interlock_would_act": num("interlock would act"), "turns": num("turns"),
         "turns_before_moves": num("turns before moves"), "lost_tasks": s["tasks"]["lost"],
         "fallback_ticks": s["planner_stats"].get("fallback_ticks_in_run"),
         "tick_callback_p99_s": s["planner_stats"]["tick_callback_s"]["p99"]}
    res["runs"][run] = f
    print("%-15s %-9s %-5s %-6d %-10d %-11.4f %-6d %-6d %-9d %-7d %-6d" % (
        run, model, turn, f["ticks"], f["delivered"], f["throughput"], f["collisions"], f["swaps"],
        f["interlock_would_act"], f["turns"], f["lost_tasks"]))
json.dump(res, open(out, "w"), indent=1, sort_keys=True)
print("written: %s" % out)
PY
