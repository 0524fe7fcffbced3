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
assert 0 < r["step_wall_time_p99_s"] <= r["step_wall_time_max_s"], r
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

# Nonsense planner and run parameters: each rejected, naming the parameter.
expect_error "gd-rhcr V < 0" "parameter V must be in \\[0," --map "$m" --planner gd-rhcr --V -1
expect_error "gd-rhcr H < 1" "parameter H must be in \\[1," --map "$m" --planner gd-rhcr --H 0
expect_error "rhcr H < 1" "parameter H must be in \\[1," --map "$m" --planner rhcr --H 0
expect_error "gd-rhcr k-threshold < 1" "parameter k-threshold must be in \\[1," --map "$m" --planner gd-rhcr --k-threshold 0
expect_error "gd-rhcr negative c-soft" "parameter c-soft must be in \\[0, 1e\\+09\\], got -0.5" --map "$m" --planner gd-rhcr --c-soft -0.5
expect_error "gd-rhcr threads 0" "parameter threads must be in \\[1," --map "$m" --planner gd-rhcr --threads 0
expect_error "rhcr alpha > H" "parameter alpha must be <= H \\(10\\)" --map "$m" --planner rhcr --H 10 --alpha 11
expect_error "rhcr timeout 0" "parameter timeout must be > 0" --map "$m" --planner rhcr --timeout 0
expect_error "gd-rhcr timeout < 0" "parameter timeout must be in" --map "$m" --planner gd-rhcr --timeout -3
expect_error "timeout nan" "parameter timeout must be a finite number" --map "$m" --planner rhcr --timeout nan
expect_error "gd-rhcr has no alpha" "unknown parameter.*alpha" --map "$m" --planner gd-rhcr --alpha 5
expect_error "pibt takes no H" "unknown parameter.*H" --map "$m" --planner pibt --H 5
expect_error "steps 0" "parameter steps must be in \\[1," --map "$m" --steps 0
expect_error "lookahead 0" "parameter lookahead must be in \\[1," --map "$m" --lookahead 0
expect_error "negative seed" "parameter seed must be a non-negative integer" --map "$m" --seed -1
expect_error "agents overflow" "parameter agents must be an integer" --map "$m" --agents 99999999999999999999

# Odd map files: a clear error naming the file and the problem.
printf 'type octile\nheight 100000\nwidth 100000\nmap\n' >"$tmp/huge.map"
printf '16777217,1\n1\n1\n1\n' >"$tmp/hugekiva.map"
: >"$tmp/empty.map"
printf '\177ELF\002\001\000\377\n' >"$tmp/binary.map"
printf 'type octile\nheight 2\nwidth 2\nmap\n' >"$tmp/header.map"
printf '3,2\n1\n1\n1\n..\n..\n' >"$tmp/lies.map"
printf 'type octile\nheight 1\nwidth 3\nmap\n.\t.\n' >"$tmp/tab.map"
expect_error "huge map header" "huge.map:4: map of 100000 x 100000 = 10000000000 cells is larger than the limit" --map "$tmp/huge.map"
expect_error "huge kiva header" "hugekiva.map:1: .*larger than the limit" --map "$tmp/hugekiva.map"
expect_error "empty map file" "empty.map: empty map file" --map "$tmp/empty.map"
expect_error "binary map file" "binary.map:1: unrecognised map format.*\\\\x7fELF" --map "$tmp/binary.map"
expect_error "header-only map" "header.map:5: truncated map: expected 2 rows, found 0" --map "$tmp/header.map"
expect_error "kiva header lies about rows" "lies.map:7: truncated map: expected 3 rows, found 2" --map "$tmp/lies.map"
expect_error "tab inside a row" "tab.map:5: unknown map symbol '\\\\x09'" --map "$tmp/tab.map"

# A map in two separate regions (x 0-3 and x 5-8).
printf 'type octile\nheight 4\nwidth 9\nmap\n....@....\n....@....\n....@....\n....@....\n' >"$tmp/split.map"
printf '6 0\n' >"$tmp/right_p.txt"
printf '8 3\n' >"$tmp/right_d.txt"
printf '0 0\n' >"$tmp/left_p.txt"
if "$sim" --map "$tmp/split.map" --agents 12 --steps 60 --seed 2 --quiet --out "$tmp/split.json" &&
   /usr/bin/python3 -c 'import json,sys; r=json.load(open(sys.argv[1])); assert r["goals_reached"] > 0 and r["throughput"] <= r["free_flow_throughput"], r' "$tmp/split.json"; then
  ok "random tasks on a split map"
else
  bad "random tasks on a split map"
fi
expect_error "MAPD pickup cannot reach a delivery" "pickup cell \\(0,0\\) cannot reach any delivery cell" \
  --map "$tmp/split.map" --tasks mapd --pickups "$tmp/left_p.txt" --deliveries "$tmp/right_d.txt"
expect_error "MAPD start cannot reach a pickup" "agent [0-9]+ at \\([0-3],[0-3]\\) cannot reach any pickup cell" \
  --map "$tmp/split.map" --tasks mapd --agents 12 --seed 2 --pickups "$tmp/right_p.txt" --deliveries "$tmp/right_d.txt"

# LoRR problems in and out (issue 12): a Start-Kit problem runs its task list; the LoRR output
# replays to the same cells as --paths; bad problems name the file and the line or field.
mkdir -p "$tmp/lorr/maps"
printf 'type octile\nheight 4\nwidth 6\nmap\nE....S\n.@@@..\n......\nS....E\n' >"$tmp/lorr/maps/small.map"
printf '3\n0\n11\n23\n' >"$tmp/lorr/agents.txt"
printf '5\n5\n18\n2\n12\n23\n' >"$tmp/lorr/tasks.txt"
printf '{"mapFile": "maps/small.map", "agentFile": "agents.txt", "teamSize": 3, "taskFile": "tasks.txt", "numTasksReveal": 1}\n' >"$tmp/lorr/problem.json"
# The Start-Kit's output in the run's model: rotation by default (MAPF_T, F/R/C/W, start facing
# east), mapf on request (PlanViz's R/L/U/D); both replay our executed paths.
for model in default mapf; do
  extra=()
  [ "$model" = mapf ] && extra=(--action-model mapf)
  if "$sim" --lorr-problem "$tmp/lorr/problem.json" --steps 40 --quiet --out "$tmp/lorr/r.json" "${extra[@]}" \
       --paths "$tmp/lorr/paths.txt" --lorr-out "$tmp/lorr/out.json" &&
     /usr/bin/python3 - "$tmp/lorr/r.json" "$tmp/lorr/paths.txt" "$tmp/lorr/out.json" "$model" <<'PY'
import json, re, sys
r = json.load(open(sys.argv[1]))
rotation = sys.argv[4] == "default"
assert r["agents"] == 3 and r["tasks"]["kind"] == "lorr" and r["params"]["lookahead"] == 1, r
assert r["action_model"] == ("rotation" if rotation else "mapf"), r["action_model"]
assert r["params"].get("turns") == ("native" if rotation else None), r["params"]
o = json.load(open(sys.argv[3]))
assert o["actionModel"] == ("MAPF_T" if rotation else "MAPF") and o["teamSize"] == 3 and o["makespan"] == 40, o
assert o["numTaskFinished"] == r["goals_reached"] > 0, (o["numTaskFinished"], r["goals_reached"])
assert o["plannerPaths"] == o["actualPaths"] and o["sumOfCost"] == 3 * 40
assert all(s[2] == ("E" if rotation else "N/A") for s in o["start"]), o["start"]
step = {"R": (1, 0), "L": (-1, 0), "U": (0, 1), "D": (0, -1), "W": (0, 0)}  # (dx, dy); U = row + 1
ahead = [(1, 0), (0, 1), (-1, 0), (0, -1)]  # E, S, W, N (rows grow downwards)
letters = set()
for line, start, moves in zip(open(sys.argv[2]), o["start"], o["actualPaths"]):
    cells = [tuple(map(int, c)) for c in re.findall(r"\((\d+),(\d+)\)", line)]
    x, y, h = start[1], start[0], 0
    replay = [(x, y)]
    for m in moves.split(","):
        letters.add(m)
        if not rotation:
            x, y = x + step[m][0], y + step[m][1]
        elif m == "F":
            x, y = x + ahead[h][0], y + ahead[h][1]
        else:
            h = (h + {"R": 1, "C": 3, "W": 0}[m]) % 4
        replay.append((x, y))
    assert replay == cells, (replay, cells)
assert ("F" in letters) == rotation and ("R" in letters or "C" in letters or not rotation), letters
PY
  then ok "LoRR problem runs ($model model); Start-Kit output replays the paths"; else bad "LoRR problem run / output ($model model)"; fi
done
printf '{"mapFile": "maps/small.map", "agentFile": "agents.txt", "taskFile": "tasks.txt"}\n' >"$tmp/lorr/noteam.json"
expect_error "LoRR problem without teamSize" "noteam.json: field \"teamSize\" is missing" --lorr-problem "$tmp/lorr/noteam.json"
printf '3\n0\n7\n23\n' >"$tmp/lorr/wall.agents"
printf '{"mapFile": "maps/small.map", "agentFile": "wall.agents", "teamSize": 3, "taskFile": "tasks.txt"}\n' >"$tmp/lorr/wall.json"
expect_error "LoRR agent on a wall names the line" "wall.agents:3: cell id 7 \\(1,1\\) is an obstacle" --lorr-problem "$tmp/lorr/wall.json"
expect_error "LoRR problem with --map" "--map cannot be combined with --lorr-problem" --lorr-problem "$tmp/lorr/problem.json" --map "$m"
expect_error "a bad --turns named" "--turns: unknown turn planning 'sideways' \\(expected native or mapf-wait\\)" --lorr-problem "$tmp/lorr/problem.json" --turns sideways

# The parameter table: --list-params prints every parameter of the planner with the value in force
# for the map and fleet (rules applied, given values marked), and runs nothing.
out=$("$sim" --planner gd-rhcr --list-params --map "$m" --agents 300 --lg-window 12 2>&1)
code=$?
if [ "$code" -eq 0 ] && grep -qE '^lg-forecast +8 ' <<<"$out" && grep -qE '^lg-window +12 \*' <<<"$out" &&
   grep -qE '^k-threshold +20 ' <<<"$out" && grep -qE '^max-density +0.02 ' <<<"$out" &&
   [ "$(grep -cE '^(preset|V|H|c-soft|lg-contraflow|lg-phases|swap) ' <<<"$out")" -eq 7 ]; then
  ok "--list-params lists the values in force"
else
  bad "--list-params (exit $code: $out)"
fi
out=$("$sim" --planner gd-rhcr --list-params --preset paper --map "$repo/maps/warehouse-10-20-10-2-1.map" --agents 400 2>&1)
if grep -qE '^guidance +none ' <<<"$out" && grep -qE '^max-density +1 ' <<<"$out"; then ok "--list-params with the paper preset"; else bad "--list-params paper ($out)"; fi
expect_error "--list-params rejects a misspelt parameter" "unknown parameter.*lg-windwo" --planner gd-rhcr --list-params --map "$m" --lg-windwo 3
expect_error "removed experiment secondary-stay" "unknown parameter.*secondary-stay" --map "$m" --planner gd-rhcr --secondary-stay 3
if "$sim" --help | grep -q -- "--lg-contraflow"; then ok "--help lists planner parameters"; else bad "--help lists no planner parameters"; fi
# The result JSON records every parameter in force and where its value came from.
"$sim" --map "$m" --planner gd-rhcr --agents 50 --steps 20 --V 3 --quiet --out "$tmp/p.json"
if /usr/bin/python3 - "$tmp/p.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
p, src = r["params"], r["param_sources"]
assert p["V"] == 3 and src["V"] == "given", (p["V"], src["V"])
assert p["lg_forecast"] == 8 and src["lg-forecast"] == "rule motion-forecast", src["lg-forecast"]
assert p["c_soft"] == 1 and src["c-soft"] == "default"
assert len(src) >= 30 and all(k.replace("-", "_") in p for k in src), sorted(src)
PY
then ok "result JSON records every parameter and its source"; else bad "result JSON params/param_sources"; fi

# Action models (issue 23): a bad model is named; the result records the model in force; a
# planner that does not plan with turns refuses the rotation model by name.
expect_error "bad action model" "action-model.*'turning'" --map "$m" --action-model turning
"$sim" --map "$m" --agents 20 --steps 10 --quiet --out "$tmp/mapf.json"
if grep -q '"action_model": "mapf"' "$tmp/mapf.json"; then ok "mapf is the default action model and is recorded"; else bad "action_model not recorded as mapf"; fi
for p in pibt rhcr gd-rhcr; do
  out=$("$sim" --map "$m" --planner "$p" --agents 20 --steps 30 --seed 2 --action-model rotation --quiet --out "$tmp/rot.json" 2>&1)
  code=$?
  if [ "$code" -eq 0 ]; then
    if /usr/bin/python3 - "$tmp/rot.json" "$p" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert r["action_model"] == "rotation" and r["params"]["action_model"] == "rotation", r["action_model"]
assert r["planner"] == sys.argv[2] and r["collisions"] == 0 and r["goals_reached"] > 0, r
assert r["throughput"] <= r["free_flow_throughput"], r
PY
    then ok "$p plans in the rotation model"; else bad "$p rotation run JSON"; fi
  elif [ "$code" -eq 2 ] && grep -qE "planner '$p' does not plan in the rotation" <<<"$out"; then
    ok "$p refuses the rotation model by name"
  else
    bad "$p --action-model rotation (exit $code: $out)"
  fi
done

# Offline preparation (issue 24 item 2): --prepare writes the choice for the map, fleet and model;
# --prep applies it (recorded as its source) unless --traffic-cost is given; a file made for
# another map or fleet is refused by name.
if "$sim" --map "$m" --planner gd-rhcr --agents 40 --steps 30 --seed 1 --action-model rotation --step-budget 0 \
     --prepare "$tmp/prep.json" --quiet >/dev/null &&
   "$sim" --map "$m" --planner gd-rhcr --agents 40 --steps 20 --action-model rotation --prep "$tmp/prep.json" \
     --quiet --out "$tmp/prepped.json" &&
   /usr/bin/python3 - "$tmp/prep.json" "$tmp/prepped.json" <<'PY'
import json, sys
prep, r = json.load(open(sys.argv[1])), json.load(open(sys.argv[2]))
assert prep["format"] == "gdrhcr-prep/2" and prep["agents"] == 40 and len(prep["trials"]) == 6, prep
assert prep["traffic_cost"] in [t["traffic_cost"] for t in prep["trials"]], prep
assert r["prep"]["applied"] and r["params"]["traffic_cost"] == prep["traffic_cost"], r["prep"]
assert r["param_sources"]["traffic-cost"].startswith("prep "), r["param_sources"]["traffic-cost"]
PY
then ok "--prepare then --prep applies the prepared traffic cost"; else bad "--prepare / --prep"; fi
expect_error "--prep for another fleet size" "made for 40 agents, not 41" --map "$m" --planner gd-rhcr --agents 41 --steps 5 --action-model rotation --prep "$tmp/prep.json"
expect_error "--prep for another map" "was made for another map" --map "$repo/maps/room-32-32-4.map" --planner gd-rhcr --agents 40 --steps 5 --action-model rotation --prep "$tmp/prep.json"
expect_error "--prepare in the mapf model" "rotation model only" --map "$m" --planner gd-rhcr --agents 40 --steps 5 --prepare "$tmp/prep2.json"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
