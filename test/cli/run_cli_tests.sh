#!/usr/bin/env bash
# gdrhcr_sim as a user runs it: a good run writes the promised JSON; bad input exits non-zero
# with a message naming the problem.  usage: run_cli_tests.sh path/to/gdrhcr_sim repo_dir
set -u
sim=$1
repo=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
pass=0
fail=0
ok() { pass=$((pass + 1)); echo "ok   - $1"; }
bad() { fail=$((fail + 1)); echo "FAIL - $1"; }

# expect_error NAME PATTERN ARGS...: exit code 2 and PATTERN in the message.
expect_error() {
  local name=$1 pattern=$2
  shift 2
  local out code
  out=$("$sim" "$@" 2>&1 >/dev/null)
  code=$?
  if [ "$code" -eq 2 ] && grep -qiE -- "$pattern" <<<"$out"; then ok "$name"; else bad "$name (exit $code: $out)"; fi
}

# A good run: JSON with every promised field, zero collisions, sensible figures, paths file.
if "$sim" --map "$repo/maps/warehouse-10-20-10-2-1.map" --tasks mapd --planner pibt --agents 200 \
     --steps 100 --seed 3 --out "$tmp/r.json" --paths "$tmp/paths.txt" --quiet; then
  if /usr/bin/python3 - "$tmp/r.json" "$tmp/paths.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
for k in ["map", "planner", "agents", "steps", "seed", "params", "throughput", "goals_reached",
          "collisions", "plan_time_mean_s", "plan_time_max_s", "wall_time_s", "free_flow_throughput"]:
    assert k in r, "missing " + k
assert r["collisions"] == 0 and r["agents"] == 200 and r["steps"] == 100 and r["seed"] == 3
assert r["planner"] == "pibt" and r["params"]["agents"] == 200
assert 0 < r["throughput"] <= r["free_flow_throughput"], r
assert abs(r["throughput"] - r["goals_reached"] / 100) < 1e-9
lines = open(sys.argv[2]).read().splitlines()
assert len(lines) == 200 and lines[0].startswith("0:") and lines[0].count("(") == 101
PY
  then ok "good run writes JSON and paths"; else bad "good run JSON content"; fi
else
  bad "good run exited non-zero"
fi

# Same seed, same result.
"$sim" --map "$repo/maps/random-32-32-20.map" --agents 50 --steps 50 --seed 9 --quiet --out "$tmp/a.json"
"$sim" --map "$repo/maps/random-32-32-20.map" --agents 50 --steps 50 --seed 9 --quiet --out "$tmp/b.json"
if [ "$(grep goals_reached "$tmp/a.json")" = "$(grep goals_reached "$tmp/b.json")" ]; then ok "seeded runs repeat"; else bad "seeded runs differ"; fi

printf 'type octile\nheight 2\nwidth 3\nmap\n...\n..\n' >"$tmp/short.map"
printf 'type octile\nheight 1\nwidth 2\nmap\n@@\n' >"$tmp/blocked.map"
printf '0 0\n' >"$tmp/cells.txt"
m="$repo/maps/random-32-32-20.map"
expect_error "missing --map" "--map is required"
expect_error "unknown option" "unknown parameter.*bogus" --map "$m" --bogus 1
expect_error "unknown planner" "unknown planner 'astar'" --map "$m" --planner astar
expect_error "nonsense agent count" "agents must be in" --map "$m" --agents -5
expect_error "non-numeric steps" "steps must be an integer" --map "$m" --steps ten
expect_error "bad task kind" "tasks must be one of" --map "$m" --tasks lifelong
expect_error "more agents than cells" "only 819 free cells" --map "$m" --agents 1000
expect_error "missing map file" "cannot open map file" --map "$tmp/none.map"
expect_error "malformed map names the line" "short.map:6" --map "$tmp/short.map"
expect_error "map without free cells" "no free cell" --map "$tmp/blocked.map"
expect_error "pickups with random tasks" "only apply to --tasks mapd" --map "$m" --pickups "$tmp/cells.txt"
expect_error "pickup on an obstacle" "obstacle" --map "$repo/maps/warehouse-10-20-10-2-1.map" --tasks mapd --pickups "$tmp/cells.txt"
expect_error "option without value" "needs a value" --map
expect_error "duplicate option" "given twice" --map "$m" --map "$m"
expect_error "positional argument" "unexpected argument" "$m"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
