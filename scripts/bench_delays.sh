#!/usr/bin/env bash
# Delay benchmark (issue 13): the headless warehouse (soak.launch without faults: planner node with
# GD-RHCR on warehouse-10-20-10-2-1 at 2 Hz, fleet_sim, a full-load task generator) with fleet_sim's
# interlock (safety stop) OFF, once without delays and once with LoRR-2026 random delays (a robot
# starts a delay with probability P_DELAY per tick, lasting 1..MAX_DELAY ticks), with the node's
# execution layer (the Action Dependency Graph). Prints figures and writes results/delays.json;
# not a test.
#   bash scripts/bench_delays.sh                                  # ROBOTS=300 DURATION=180
#   ROBOTS=50 DURATION=60 bash scripts/bench_delays.sh
# Environment: ROBOTS (300), DURATION (s per run, 180), P_DELAY (0.01), MAX_DELAY (20 ticks),
# SPEED_SPREAD (0: every robot takes move_fraction of a tick per move), PLANNER (gd-rhcr),
# EXECUTIONS (adg, the only execution since issue 22; kept so older command lines still run),
# SEED (1), OUT (results/delays.json), CONFIG (the node's parameter file; default config/fleet.yaml:
# a copy with other values, e.g. catch_up: 0, compares a setting). Installs and builds what it needs (scripts/ros_env.sh;
# GDRHCR_SKIP_BUILD=1 uses the workspace as it is). Holds /tmp/gdrhcr_ros.lock while it runs (one ROS run at a time).
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
ROBOTS=${ROBOTS:-300}
DURATION=${DURATION:-180}
P_DELAY=${P_DELAY:-0.01}
MAX_DELAY=${MAX_DELAY:-20}
SPEED_SPREAD=${SPEED_SPREAD:-0.0}
PLANNER=${PLANNER:-gd-rhcr}
EXECUTIONS=${EXECUTIONS:-adg}
for ex in $EXECUTIONS; do
  if [ "$ex" != adg ]; then
    echo "bench_delays: EXECUTIONS='$EXECUTIONS': adg is the only execution (lock-step was removed in issue 22)" >&2
    exit 2
  fi
done
EXECUTIONS=adg
SEED=${SEED:-1}
OUT=${OUT:-$top/results/delays.json}
CONFIG=${CONFIG:-$top/config/fleet.yaml}
[ -f "$CONFIG" ] || { echo "bench_delays: CONFIG='$CONFIG' is not a file" >&2; exit 2; }
CONFIG=$(cd "$(dirname "$CONFIG")" && pwd)/$(basename "$CONFIG")
# shellcheck source=ros_env.sh
source "$top/scripts/ros_env.sh"
export ROS_MASTER_URI=http://127.0.0.1:11712
mkdir -p "$top/results" "$ROS_HOME"
runs=()
for ex in $EXECUTIONS; do
  for p in 0 "$P_DELAY"; do
    out="$ROS_HOME/bench_delays_${ex}_p${p}.json"
    rm -f "$out"
    echo "bench_delays: $ex, $ROBOTS robots, p_delay $p, D $MAX_DELAY, interlock off, ${DURATION}s -> $out"
    flock /tmp/gdrhcr_ros.lock roslaunch -p 11712 gd_rhcr_planner soak.launch faults:=false \
      num_robots:="$ROBOTS" planner:="$PLANNER" seed:="$SEED" duration:="$DURATION" robot_steps:=1000000000 \
      p_delay:="$p" max_delay_ticks:="$MAX_DELAY" speed_spread:="$SPEED_SPREAD" interlock:=false \
      config:="$CONFIG" output:="$out" >"$ROS_HOME/bench_delays_${ex}_p${p}.log" 2>&1 || true
    runs+=("$ex" "$p" "$out")
  done
done
commit=$(git -C "$top" rev-parse --short HEAD 2>/dev/null || echo unknown)
/usr/bin/python3 - "$OUT" "$ROBOTS" "$DURATION" "$P_DELAY" "$MAX_DELAY" "$SPEED_SPREAD" "$PLANNER" "$SEED" "$commit" "${runs[@]}" <<'PY'
import json, sys
out, robots, duration, p_delay, max_delay, spread, planner, seed, commit = sys.argv[1:10]
rest = sys.argv[10:]
runs = {}
for i in range(0, len(rest), 3):
    ex, p, path = rest[i:i + 3]
    try:
        s = json.load(open(path))
    except (OSError, ValueError) as e:
        print("%s: no result (%s)" % (path, e))
        s = None
    runs.setdefault(ex, {})["delay" if float(p) > 0 else "no_delay"] = s


def figures(s):
    if s is None:
        return None
    d = s.get("fleet_sim_diagnostics", {})
    num = lambda k: int(float(d.get(k, 0)))
    ticks = max(1, s["ticks"])
    return {
        "ticks": s["ticks"],
        "delivered": s["tasks"]["delivered"],
        "throughput": round(s["tasks"]["delivered"] / ticks, 4),  # deliveries per tick
        "collisions": num("collisions"),            # fleet_sim: a robot arrived in an occupied cell
        "swaps": num("swaps"),                       # fleet_sim: two robots started into each other's cells
        "vertex_collisions_reported": s["safety"]["vertex_collisions"],  # soak_benchmark, from robot_states
        "swaps_reported": s["safety"]["swaps"],
        "jumps_reported": s["safety"]["jumps"],
        "interlock_would_act": num("interlock would act"),
        "delays_started": num("delays started"),
        "lost_tasks": s["tasks"]["lost"],
        "unacknowledged_tasks": s["tasks"]["unacknowledged"],
        "overruns": s["planner_stats"].get("overruns_in_run"),
        "fallback_ticks": s["planner_stats"].get("fallback_ticks_in_run"),
        "tick_callback_p99_s": s["planner_stats"]["tick_callback_s"]["p99"],
    }


res = {"robots": int(robots), "duration_s": float(duration), "p_delay": float(p_delay),
       "max_delay_ticks": int(max_delay), "speed_spread": float(spread), "planner": planner,
       "map": "warehouse-10-20-10-2-1", "tick_rate_hz": 2.0, "interlock": "off", "seed": int(seed),
       "commit": commit, "node_parameters": "config/fleet.yaml at that commit",
       "command": "ROBOTS=%s DURATION=%s bash scripts/bench_delays.sh" % (robots, duration)}
for ex, r in runs.items():
    nd, de = figures(r.get("no_delay")), figures(r.get("delay"))
    block = {"no_delay": nd, "delay": de}
    if nd and de:
        block.update({
            "throughput_no_delay": nd["throughput"], "throughput_delay": de["throughput"],
            "throughput_ratio": round(de["throughput"] / nd["throughput"], 3) if nd["throughput"] else None,
            # the larger of fleet_sim's physical count and what the robots' reports show
            "collisions": max(de["collisions"], de["vertex_collisions_reported"]),
            "swaps": max(de["swaps"], de["swaps_reported"]), "interlock_would_act": de["interlock_would_act"], "lost_tasks": de["lost_tasks"]})
    res[ex] = block
main = res.get("adg")
if main and "throughput_delay" in main:  # the headline fields are the default execution's (adg)
    for k in ("throughput_no_delay", "throughput_delay", "throughput_ratio", "collisions", "swaps",
              "interlock_would_act", "lost_tasks"):
        res[k] = main[k]
json.dump(res, open(out, "w"), indent=1, sort_keys=True)
print("\n%-9s %-9s %-7s %-10s %-11s %-6s %-10s %-9s %-6s" % (
    "execution", "delays", "ticks", "delivered", "throughput", "coll.", "swaps", "interlock", "lost"))
for ex in runs:
    for k in ("no_delay", "delay"):
        f = res[ex].get(k)
        if not f:
            print("%-9s %-9s no result" % (ex, k)); continue
        print("%-9s %-9s %-7d %-10d %-11.4f %-6d %-10d %-9d %-6d" % (
            ex, k, f["ticks"], f["delivered"], f["throughput"], max(f["collisions"], f["vertex_collisions_reported"]),
            max(f["swaps"], f["swaps_reported"]), f["interlock_would_act"], f["lost_tasks"]))
    if "throughput_ratio" in res[ex]:
        print("%-9s throughput with delays / without: %.3f" % (ex, res[ex]["throughput_ratio"]))
print("written: %s" % out)
PY
