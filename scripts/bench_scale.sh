#!/usr/bin/env bash
# Fleets of thousands of robots (issue 12): GD-RHCR (--threads 2) and PIBT with random goals on
# large maps; ms per step (mean, p99), peak RSS, throughput, BFS runs, GD-RHCR/PIBT throughput.
# Prints figures; not a test. Each run is its own process, so peak RSS is per run. "ms/step" is
# plan_step's wall time; "loop ms/step" runs from one plan_step to the next and so also holds the
# simulator's BFS of new current goals (done outside plan_step since the lateness figures).
#   scripts/bench_scale.sh [BUILD_DIR]        (default build/)
# Environment (defaults in brackets):
#   AGENTS   ["2000 5000 10000"]
#   MAPS     ["maps/warehouse-20-40-10-2-2.map maps/lorr-warehouse-140-500.map"]
#   PLANNERS ["pibt gd-rhcr"]      STEPS [300]   SEED [1]   LOOKAHEAD [3]
#   BUDGET_MB [1024]  distance-table budget: 10,000 agents hold ~10,000 rows of 2 bytes per free
#                     cell (77.6 KB on warehouse-20-40-10-2-2) at once, so 256 MB would thrash
#   THREADS [2]       GD-RHCR threads      NICE [10]
#   OUT ["bench_scale.jsonl"]  one JSON line per run (appended); the table is built from it
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$top/build}
bin=$build/src/bench_scale
[ -x "$bin" ] || { echo "bench_scale: $bin not built (cmake --build $build --target bench_scale)" >&2; exit 2; }
AGENTS=${AGENTS:-"2000 5000 10000"}
MAPS=${MAPS:-"maps/warehouse-20-40-10-2-2.map maps/lorr-warehouse-140-500.map"}
PLANNERS=${PLANNERS:-"pibt gd-rhcr"}
STEPS=${STEPS:-300}
SEED=${SEED:-1}
LOOKAHEAD=${LOOKAHEAD:-3}
BUDGET_MB=${BUDGET_MB:-1024}
THREADS=${THREADS:-2}
NICE=${NICE:-10}
OUT=${OUT:-bench_scale.jsonl}

for map in $MAPS; do
  [ -f "$map" ] || map=$top/$map
  for n in $AGENTS; do
    for planner in $PLANNERS; do
      extra=()
      [ "$planner" = gd-rhcr ] && extra=(--threads "$THREADS")
      echo "--- $planner, $n agents, $(basename "$map"), $STEPS steps" >&2
      nice -n "$NICE" "$bin" --map "$map" --planner "$planner" --agents "$n" --steps "$STEPS" --seed "$SEED" \
        --lookahead "$LOOKAHEAD" --dist-budget-mb "$BUDGET_MB" --json "$OUT" "${extra[@]}" >&2
    done
  done
done

/usr/bin/python3 - "$OUT" <<'PY'
import json, os, sys
runs = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
last = {}
for r in runs:  # the latest run of each configuration
    last[(os.path.basename(r["map"]), r["agents"], r["planner"], r["steps"])] = r
print("| map | agents | planner | steps | ms/step mean | p99 | CPU ms/step | loop ms/step mean | loop p99 | peak RSS MB | throughput | BFS runs | GD-RHCR / PIBT |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for (m, n, p, s), r in sorted(last.items()):
    pibt = last.get((m, n, "pibt", s))
    ratio = "%.2f" % (r["throughput"] / pibt["throughput"]) if p != "pibt" and pibt and pibt["throughput"] > 0 else ""
    print("| %s | %d | %s | %d | %.1f | %.1f | %.1f | %.1f | %.1f | %.0f | %.3f | %d | %s |" % (
        m, n, p, s, r["ms_per_step_mean"], r["ms_per_step_p99"], r.get("cpu_ms_per_step_mean", float("nan")),
        r.get("loop_ms_per_step_mean", float("nan")), r.get("loop_ms_per_step_p99", float("nan")),
        r["peak_rss_mb"], r["throughput"],
        r["bfs_runs"], ratio))
PY
