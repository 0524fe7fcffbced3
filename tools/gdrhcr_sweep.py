#!/usr/bin/env python3
"""gdrhcr_sweep: runs maps x planners x agent counts x seeds with gdrhcr_sim, in parallel
processes, into one tidy CSV. Stop it any time (Ctrl-C, kill); run it again with the same
arguments and it resumes, skipping every run already in the CSV.

    tools/gdrhcr_sweep.py config/experiments/smoke.yaml --out results/smoke.csv --jobs 2

A config (YAML):
    name: warehouse1            # free text, recorded in every row
    steps: 500
    seeds: 30                   # a count (seeds 0..29) or a list
    sim: build/src/gdrhcr_sim   # optional; default build/src/gdrhcr_sim of this checkout
    experiments:
      - map: maps/warehouse-10-20-10-2-1.map
        tasks: mapd             # random | mapd
        agents: [100, 200, 400]
        planners:               # each: a label and gdrhcr_sim options
          - {label: GD-RHCR, planner: gd-rhcr, V: 2, H: 20, c-soft: 1}
          - {label: RHCR, planner: rhcr, H: 20, alpha: 5, timeout: 60}
          - {label: PIBT, planner: pibt}
Options given as `k_threshold_fraction: 0.1` with `k_threshold_cap: 20` compute
--k-threshold = max(2, min(floor(f * agents), cap)) per agent count (the paper's rule).
"""
import argparse
import concurrent.futures as cf
import csv
import json
import math
import os
import subprocess
import sys
import tempfile
import threading
import time

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))

KEY = ["label", "map", "tasks", "agents", "seed", "steps"]
FIELDS = KEY + [
    "sweep", "planner", "params", "throughput", "goals_reached", "free_flow_throughput",
    "collisions", "plan_time_mean_s", "plan_time_max_s", "planned_steps", "step_wall_time_mean_s",
    "wall_time_s", "groups_mean_count", "groups_mean_size", "groups_mean_max_size",
    "groups_replanned_per_step", "cache_reuses", "threshold_fallbacks", "failure_fallbacks",
    "solver_calls", "solver_failures", "status", "error",
]


class ConfigError(Exception):
    pass


def load_config(path):
    with open(path) as f:
        cfg = yaml.safe_load(f)
    if not isinstance(cfg, dict) or "experiments" not in cfg:
        raise ConfigError("%s: expected a mapping with an 'experiments' list" % path)
    return cfg


def expand(cfg):
    """All runs of a config, as dicts with the KEY fields and the sim options."""
    steps = int(cfg.get("steps", 500))
    seeds = cfg.get("seeds", 1)
    seeds = list(range(int(seeds))) if isinstance(seeds, int) else [int(s) for s in seeds]
    runs = []
    for e, exp in enumerate(cfg["experiments"]):
        for field in ("map", "agents", "planners"):
            if field not in exp:
                raise ConfigError("experiment %d: missing '%s'" % (e, field))
        tasks = exp.get("tasks", "random")
        for p in exp["planners"]:
            p = dict(p)
            label = str(p.pop("label", p.get("planner", "pibt")))
            frac = p.pop("k_threshold_fraction", None)
            cap = p.pop("k_threshold_cap", None)
            for agents in exp["agents"]:
                opts = dict(p)
                if frac is not None:
                    opts["k-threshold"] = max(2, min(int(math.floor(frac * agents)), int(cap or 20)))
                for seed in seeds:
                    runs.append({"label": label, "map": exp["map"], "tasks": tasks,
                                 "agents": int(agents), "seed": seed, "steps": steps,
                                 "options": opts})
    return runs


def run_key(row):
    return tuple(str(row[k]) for k in KEY)


def read_done(path):
    """Keys of the finished runs in an existing CSV; drops a torn last line left by a kill."""
    if not os.path.exists(path):
        return set()
    with open(path, newline="") as f:
        text = f.read()
    if text and not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
        with open(path, "w", newline="") as f:
            f.write(text)
    rows = list(csv.DictReader(text.splitlines()))
    return {run_key(r) for r in rows if r.get("status") == "ok" and len(r) == len(FIELDS)}


def drop_unfinished(path, done):
    """Rewrite the CSV keeping only finished ('ok') rows, so failed runs are retried."""
    if not os.path.exists(path):
        return
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if run_key(r) in done and r.get("status") == "ok"]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)


def execute(sim, run):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "r.json")
        cmd = [sim, "--map", os.path.join(ROOT, run["map"]) if not os.path.isabs(run["map"]) else run["map"],
               "--tasks", run["tasks"], "--agents", str(run["agents"]), "--seed", str(run["seed"]),
               "--steps", str(run["steps"]), "--out", out, "--quiet"]
        for k, v in run["options"].items():
            cmd += ["--" + str(k), str(v)]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        row = {k: run[k] for k in KEY}
        row["planner"] = run["options"].get("planner", "pibt")
        if proc.returncode != 0:
            row["status"] = "collision" if proc.returncode == 3 else "error"
            row["error"] = proc.stderr.strip().replace("\n", " ")[:500]
            return row
        with open(out) as f:
            r = json.load(f)
    st = r.get("stats", {})
    g = st.get("groups", {})
    row.update({
        "params": json.dumps(r["params"], sort_keys=True), "throughput": r["throughput"],
        "goals_reached": r["goals_reached"], "free_flow_throughput": r["free_flow_throughput"],
        "collisions": r["collisions"], "plan_time_mean_s": r["plan_time_mean_s"],
        "plan_time_max_s": r["plan_time_max_s"], "planned_steps": r["planned_steps"],
        "step_wall_time_mean_s": r["step_wall_time_mean_s"], "wall_time_s": r["wall_time_s"],
        "groups_mean_count": g.get("mean_count", ""), "groups_mean_size": g.get("mean_size", ""),
        "groups_mean_max_size": g.get("mean_max_size", ""),
        "groups_replanned_per_step": g.get("replanned_per_step", ""),
        "cache_reuses": st.get("cache_reuses", ""), "threshold_fallbacks": st.get("threshold_fallbacks", ""),
        "failure_fallbacks": st.get("failure_fallbacks", ""), "solver_calls": st.get("solver_calls", st.get("primary_calls", "")),
        "solver_failures": st.get("solver_failures", ""), "status": "ok", "error": "",
    })
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("config")
    ap.add_argument("--out", required=True, help="the CSV (created or resumed)")
    ap.add_argument("--jobs", type=int, default=max(1, (os.cpu_count() or 2)))
    ap.add_argument("--sim", help="gdrhcr_sim binary (default: config 'sim' or build/src/gdrhcr_sim)")
    ap.add_argument("--limit", type=int, default=0, help="run at most this many new runs (0 = all)")
    args = ap.parse_args(argv)
    if args.jobs < 1:
        ap.error("--jobs must be at least 1")
    try:
        cfg = load_config(args.config)
        runs = expand(cfg)
    except (OSError, yaml.YAMLError, ConfigError, ValueError, TypeError) as e:
        print("gdrhcr_sweep: bad config: %s" % e, file=sys.stderr)
        return 2
    sim = args.sim or cfg.get("sim") or os.path.join(ROOT, "build", "src", "gdrhcr_sim")
    if not os.path.isabs(sim):
        sim = os.path.join(ROOT, sim)
    if not os.access(sim, os.X_OK):
        print("gdrhcr_sweep: simulator not found at %s (build it with scripts/build_core.sh)" % sim, file=sys.stderr)
        return 2
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    done = read_done(args.out)
    drop_unfinished(args.out, done)
    todo = [r for r in runs if run_key(r) not in done]
    if args.limit:
        todo = todo[: args.limit]
    print("gdrhcr_sweep: %d runs in config, %d already done, %d to run with %d jobs"
          % (len(runs), len(runs) - len([r for r in runs if run_key(r) not in done]), len(todo), args.jobs))
    new_file = not os.path.exists(args.out) or os.path.getsize(args.out) == 0
    lock = threading.Lock()
    failures = 0
    t0 = time.time()
    with open(args.out, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        if new_file:
            writer.writeheader()
            f.flush()
        with cf.ThreadPoolExecutor(max_workers=args.jobs) as pool:
            futures = {pool.submit(execute, sim, r): r for r in todo}
            for k, fut in enumerate(cf.as_completed(futures), 1):
                row = fut.result()
                row["sweep"] = cfg.get("name", os.path.basename(args.config))
                with lock:
                    writer.writerow(row)  # one whole line per run, flushed: a kill tears at most one
                    f.flush()
                    os.fsync(f.fileno())
                elapsed = time.time() - t0
                eta = elapsed / k * (len(todo) - k)
                if row["status"] != "ok":
                    failures += 1
                summary = ("throughput %.3f" % row["throughput"]) if row["status"] == "ok" else row["status"] + ": " + row["error"][:120]
                print("[%d/%d] %s %s agents=%s seed=%s: %s | elapsed %ds, ETA %ds"
                      % (k, len(todo), row["label"], os.path.basename(row["map"]), row["agents"],
                         row["seed"], summary, elapsed, eta), flush=True)
    print("gdrhcr_sweep: finished, %d failed runs (kept with their status; rerun to retry)" % failures)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
