#!/usr/bin/env bash
# Runs our planner in the League of Robot Runners' own simulator (issue 23, item 3):
#   bash scripts/bench_lorr.sh START_KIT_DIR INSTANCE_JSON STEPS OUT_JSON [BUDGET_MS]
# Builds out of tree: copies the Start-Kit (v1.1.5; it stays outside the repository) to
# $LORR_BUILD (default build/lorr), puts lorr_adapter/MAPFPlanner.{h,cpp} in place of its
# MAPFPlanner, links our core library (build/, built here if needed), runs the Start-Kit's
# `lifelong` on INSTANCE_JSON for STEPS timesteps with the League's limits (planTimeLimit 1 s per
# step, preprocessTimeLimit 1800 s) and leaves the Start-Kit's output JSON at OUT_JSON
# (numTaskFinished, AllValid, errors, plannerTimes, ...). BUDGET_MS caps our planner's time per
# step below the League's 1 s (default 0 = no cap of ours). Our own time per step (the adapter's
# clock, from the Start-Kit's call to our answer) goes to OUT_JSON with .times for .json, one line
# (ms) per step.
# Our planner: GDRHCR_PLANNER (default gd-rhcr, any name of gdrhcr_sim --planner) and
# GDRHCR_PARAMS (its parameters, e.g. "--H 10 --V 3"); GDRHCR_SEED. See lorr_adapter/lorr_bridge.hpp.
# Prints one summary line; exits non-zero if the build or the run fails.
set -eo pipefail
if [ $# -lt 4 ] || [ $# -gt 5 ]; then
  echo "usage: bash scripts/bench_lorr.sh START_KIT_DIR INSTANCE_JSON STEPS OUT_JSON [BUDGET_MS]" >&2
  exit 2
fi
top=$(cd "$(dirname "$0")/.." && pwd)
kit_arg=$1 instance=$2 steps=$3 out=$4 budget=${5:-0}
[ -f "$kit_arg/src/driver.cpp" ] && [ -f "$kit_arg/inc/MAPFPlanner.h" ] ||
  { echo "bench_lorr: $kit_arg is not a LoRR Start-Kit (no src/driver.cpp, inc/MAPFPlanner.h)" >&2; exit 2; }
[ -f "$instance" ] || { echo "bench_lorr: no instance file $instance" >&2; exit 2; }
[[ "$steps" =~ ^[1-9][0-9]*$ ]] || { echo "bench_lorr: STEPS must be a positive integer, not '$steps'" >&2; exit 2; }
[[ "$budget" =~ ^[0-9]+(\.[0-9]+)?$ ]] || { echo "bench_lorr: BUDGET_MS must be a number, not '$budget'" >&2; exit 2; }
kit=$(cd "$kit_arg" && pwd)
instance=$(cd "$(dirname "$instance")" && pwd)/$(basename "$instance")
mkdir -p "$(dirname "$out")"
out=$(cd "$(dirname "$out")" && pwd)/$(basename "$out")
build=${LORR_BUILD:-$top/build/lorr}
jobs=${LORR_JOBS:-2}

# Our core library.
if [ ! -f "$top/build/CMakeCache.txt" ]; then
  cmake -S "$top" -B "$top/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
cmake --build "$top/build" --target gdrhcr_core -j"$jobs" >/dev/null

# The Start-Kit copy with our MAPFPlanner (timestamps kept, so a rebuild only compiles what changed).
if [ "$(cat "$build/start-kit.from" 2>/dev/null)" != "$kit" ]; then
  rm -rf "$build"
  mkdir -p "$build"
fi
mkdir -p "$build/start-kit"
cp -a "$kit/inc" "$kit/src" "$build/start-kit/"
[ -f "$kit/version.txt" ] && cp -a "$kit/version.txt" "$build/start-kit/"
cp -p "$top/lorr_adapter/MAPFPlanner.h" "$build/start-kit/inc/MAPFPlanner.h"
cp -p "$top/lorr_adapter/MAPFPlanner.cpp" "$build/start-kit/src/MAPFPlanner.cpp"
echo "$kit" >"$build/start-kit.from"
cmake -S "$top/lorr_adapter" -B "$build/cmake" -DCMAKE_BUILD_TYPE=Release \
  -DSTART_KIT_COPY="$build/start-kit" -DGDRHCR_BUILD="$top/build" >"$build/cmake.log" 2>&1 ||
  { cat "$build/cmake.log" >&2; echo "bench_lorr: configuring the adapter failed" >&2; exit 1; }
cmake --build "$build/cmake" -j"$jobs" >"$build/build.log" 2>&1 ||
  { tail -40 "$build/build.log" >&2; echo "bench_lorr: building the adapter failed (see $build/build.log)" >&2; exit 1; }

# The run, with the League's limits.
rm -f "$out"
log=${out%.json}.log
export GDRHCR_BUDGET_MS=$budget
export GDRHCR_TIMES_OUT=${out%.json}.times
set +e
"$build/cmake/lifelong" --inputFile "$instance" --output "$out" --simulationTime "$steps" \
  --planTimeLimit "${LORR_PLAN_TIME_LIMIT:-1}" --preprocessTimeLimit "${LORR_PREPROCESS_TIME_LIMIT:-1800}" \
  --logFile "$log" >"${out%.json}.stdout" 2>"${out%.json}.stderr"
rc=$?
set -e
cat "${out%.json}.stderr" >&2
if [ $rc -ne 0 ] || [ ! -f "$out" ]; then
  echo "bench_lorr: lifelong exited with $rc (stdout ${out%.json}.stdout, log $log)" >&2
  exit 1
fi
/usr/bin/python3 - "$out" "$instance" "$steps" "$budget" "$GDRHCR_TIMES_OUT" <<'PY'
import json, sys
out, instance, steps, budget, times_out = sys.argv[1:]
r = json.load(open(out))
times = r.get("plannerTimes", [])
ms = 1000 * sum(times) / len(times) if times else float("nan")
ours = sorted(float(x) for x in open(times_out).read().split())
p99 = ours[min(len(ours) - 1, int(0.99 * len(ours)))] if ours else float("nan")
mean = sum(ours) / len(ours) if ours else float("nan")
print(f"bench_lorr: {instance} {steps} steps, budget {budget} ms: numTaskFinished {r['numTaskFinished']}, "
      f"AllValid {r['AllValid']}, errors {len(r.get('errors', []))}, "
      f"planner {ms:.1f} ms per step (max {1000 * max(times, default=0):.1f}) by the Start-Kit, "
      f"ours mean {mean:.1f} p99 {p99:.1f} max {max(ours, default=float('nan')):.1f} ms, output {out}")
PY
