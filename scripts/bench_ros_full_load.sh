#!/usr/bin/env bash
# Full-load tick benchmark of the ROS planner node: for each robot count, the simulated
# warehouse (soak.launch without faults: planner node with GD-RHCR, fleet_sim, a task generator
# keeping 2 x robots tasks open so every robot is busy) runs DURATION s at 2 Hz while
# soak_benchmark.py records every tick; then prints tick-callback and plan-time percentiles,
# overruns, PIBT fallback ticks, busy robots and deliveries per robot count.
#   bash scripts/bench_ros_full_load.sh                 # ROBOTS="100 500 1000" DURATION=120
#   ROBOTS="200" DURATION=60 PLANNER=pibt bash scripts/bench_ros_full_load.sh
# JSON per run: results/ros_full_load_<planner>_<robots>.json. Installs and builds what it needs
# (scripts/ros_env.sh; GDRHCR_SKIP_BUILD=1 uses the workspace as it is). Uses its own ROS master port (11711) so it does not meet other runs.
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
ROBOTS=${ROBOTS:-"100 500 1000"}
DURATION=${DURATION:-120}
PLANNER=${PLANNER:-gd-rhcr}
TICK_RATE=${TICK_RATE:-2.0}
# shellcheck source=ros_env.sh
source "$top/scripts/ros_env.sh"
export ROS_MASTER_URI=http://127.0.0.1:11711
mkdir -p "$top/results"
files=()
for n in $ROBOTS; do
  out="$top/results/ros_full_load_${PLANNER}_${n}.json"
  echo "bench_ros_full_load: $n robots, $PLANNER, ${DURATION}s at ${TICK_RATE} Hz -> $out"
  roslaunch -p 11711 gd_rhcr_planner soak.launch faults:=false num_robots:="$n" planner:="$PLANNER" \
    tick_rate:="$TICK_RATE" duration:="$DURATION" robot_steps:=1000000000 output:="$out" \
    >"$ROS_HOME/bench_full_load_$n.log" 2>&1 || true
  files+=("$out")
done
/usr/bin/python3 - "${files[@]}" <<'PY'
import json, sys
print("\n%-7s %-6s %-44s %-26s %-9s %-9s %-11s %-9s %s" % (
    "robots", "ticks", "tick callback p50/p90/p99/max [s]", "plan time p50/p99/max [s]",
    "overruns", "fallback", "busy (p50)", "delivered", "safety"))
for path in sys.argv[1:]:
    try:
        s = json.load(open(path))
    except (OSError, ValueError) as e:
        print("%s: no result (%s)" % (path, e)); continue
    ps, t, sa = s["planner_stats"], s["tasks"], s["safety"]
    cb, pt = ps["tick_callback_s"], ps["plan_time_s"]
    busy = "%s/%d" % (t.get("robots_busy_median"), s["robots"])
    ok = sa["vertex_collisions"] == 0 and sa["swaps"] == 0 and sa["jumps"] == 0 and t["lost"] == 0
    print("%-7d %-6d %-44s %-26s %-9s %-9s %-11s %-9d %s" % (
        s["robots"], s["ticks"],
        "%.4f / %.4f / %.4f / %.4f" % (cb["p50"], cb["p90"], cb["p99"], cb["max"]),
        "%.4f / %.4f / %.4f" % (pt["p50"], pt["p99"], pt["max"]),
        ps["overruns_in_run"], ps["fallback_ticks_in_run"], busy, t["delivered"],
        "ok" if ok else "FAILED: %s" % s["failures"]))
PY
