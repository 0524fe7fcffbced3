#!/usr/bin/env bash
# CI test of the LoRR adapter and of gdrhcr_sim's LoRR semantics (issue 23): our GD-RHCR as the
# Start-Kit's MAPFPlanner on a small instance (test/lorr/small: a 12 x 8 map with 'O' and 'W'
# cells, which LoRR treats as free, and a walled-in cell; 6 agents, one starting on a 'W';
# tasks on a start cell, repeated tasks and one unreachable task; 60 steps), refereed by the
# Start-Kit's own simulator. Fails unless the Start-Kit reports AllValid Yes, no error, no
# timed-out step and finished tasks, and unless `gdrhcr_sim --lorr-problem --lorr-out` on the
# same instance writes the very same output (actions, starts, tasks finished, events, tasks,
# costs): the same planner (deterministic: no time budget here) in the same rules.
# The Start-Kit (v1.1.5) stays outside the repository: $LORR_START_KIT, else
# ../shared/lorr/start-kit-v1.1.5 next to the repository, else /work/shared/lorr/start-kit-v1.1.5.
set -eo pipefail
top=$(cd "$(dirname "$0")/.." && pwd)
kit=${LORR_START_KIT:-}
if [ -z "$kit" ]; then
  for c in "$top/../shared/lorr/start-kit-v1.1.5" /work/shared/lorr/start-kit-v1.1.5; do
    [ -f "$c/src/driver.cpp" ] && { kit=$c; break; }
  done
fi
if [ -n "${LORR_START_KIT:-}" ] && [ ! -f "$kit/src/driver.cpp" ]; then
  echo "lorr_test: FAIL: LORR_START_KIT=$LORR_START_KIT is not a LoRR Start-Kit (no src/driver.cpp);" \
       "set it to the Start-Kit v1.1.5 directory" >&2
  exit 1
fi
if [ -z "$kit" ]; then
  echo "lorr_test: FAIL: no LoRR Start-Kit found in $top/../shared/lorr/start-kit-v1.1.5 or" \
       "/work/shared/lorr/start-kit-v1.1.5; set LORR_START_KIT to the Start-Kit v1.1.5 directory" >&2
  exit 1
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
instance=$top/test/lorr/small/small.json
bash "$top/scripts/bench_lorr.sh" "$kit" "$instance" 60 "$tmp/out.json" 0
cmake --build "$top/build" --target gdrhcr_sim -j2 >/dev/null
"$top/build/src/gdrhcr_sim" --lorr-problem "$instance" --planner gd-rhcr --steps 60 --quiet \
  --out "$tmp/sim.json" --lorr-out "$tmp/ours.json"
/usr/bin/python3 - "$tmp/out.json" "$tmp/ours.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
ours = json.load(open(sys.argv[2]))
problems = []
for key in ["actionModel", "AllValid", "teamSize", "start", "numTaskFinished", "sumOfCost", "makespan",
            "actualPaths", "plannerPaths", "errors", "events", "tasks"]:
    if ours.get(key) != r.get(key):
        problems.append(f"gdrhcr_sim --lorr-out differs from the Start-Kit in {key!r}")
if r.get("AllValid") != "Yes": problems.append(f"AllValid is {r.get('AllValid')!r}")
if r.get("errors"): problems.append(f"errors: {r['errors'][:5]}")
if r.get("actionModel") != "MAPF_T": problems.append(f"actionModel {r.get('actionModel')!r}")
paths = r.get("actualPaths", [])
if len(paths) != 6 or any(len(p.split(",")) != 60 for p in paths): problems.append("not 6 paths of 60 actions")
if any("T" in p.split(",") for p in r.get("plannerPaths", [])): problems.append("a planner step timed out (T)")
if r.get("plannerPaths") != paths: problems.append("executed actions differ from the planner's")
if not any("F" in p.split(",") for p in paths): problems.append("no agent ever moved forward")
if r.get("numTaskFinished", 0) < 5: problems.append(f"only {r.get('numTaskFinished')} tasks finished")
if problems:
    print("lorr_test: FAIL: " + "; ".join(problems))
    sys.exit(1)
print(f"lorr_test: OK: AllValid Yes, no errors, {r['numTaskFinished']} tasks finished in 60 steps; "
      "gdrhcr_sim --lorr-problem writes the same output")
PY

# With a budget of our own (100 ms per step, far below the Start-Kit's 1 s): every cell's distance
# row in the preprocessing phase, then planning within the budget; still valid, and tasks are
# finished.
bash "$top/scripts/bench_lorr.sh" "$kit" "$instance" 60 "$tmp/capped.json" 100 2>"$tmp/capped.err" >/dev/null ||
  { cat "$tmp/capped.err"; echo "lorr_test: FAIL: the run with a 100 ms budget"; exit 1; }
/usr/bin/python3 - "$tmp/capped.json" "$tmp/capped.times" <<'PY' || exit 1
import json, sys
r = json.load(open(sys.argv[1]))
steps = open(sys.argv[2]).read().split()
problems = []
if r.get("AllValid") != "Yes" or r.get("errors"): problems.append(f"AllValid {r.get('AllValid')!r}, errors {r.get('errors', [])[:5]}")
if r.get("numTaskFinished", 0) < 5: problems.append(f"only {r.get('numTaskFinished')} tasks finished")
if len(steps) != 60: problems.append(f"{len(steps)} step times recorded, not 60")
if problems:
    print("lorr_test: FAIL with a 100 ms budget: " + "; ".join(problems))
    sys.exit(1)
print(f"lorr_test: OK with a 100 ms budget: {r['numTaskFinished']} tasks finished, AllValid Yes")
PY
# Offline preparation in the Start-Kit's preprocessing phase (issue 24 item 2): the first run
# makes the file for this map and fleet in GDRHCR_PREP_DIR, the second loads it; both valid.
mkdir -p "$tmp/prep"
for run in 1 2; do
  GDRHCR_PREP_DIR=$tmp/prep bash "$top/scripts/bench_lorr.sh" "$kit" "$instance" 60 "$tmp/prep$run.json" 0 \
    2>"$tmp/prep$run.err" >/dev/null || { cat "$tmp/prep$run.err"; echo "lorr_test: FAIL: run $run with GDRHCR_PREP_DIR"; exit 1; }
  grep -q '"AllValid": "Yes"' "$tmp/prep$run.json" || { echo "lorr_test: FAIL: run $run with a preparation is not valid"; exit 1; }
done
files=("$tmp"/prep/gdrhcr-prep-*-6-rotation.json)
grep -q "no preparation file .* yet; preparing" "$tmp/prep1.err" && grep -q "preparation loaded from" "$tmp/prep2.err" &&
  [ -f "${files[0]}" ] || { cat "$tmp/prep1.err" "$tmp/prep2.err"; echo "lorr_test: FAIL: the preparation was not made, cached and loaded"; exit 1; }
echo "lorr_test: OK: the preparation was made in the first run's preprocessing and loaded in the second"
