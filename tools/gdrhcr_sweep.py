#!/usr/bin/env python3
"""gdrhcr_sweep: runs maps x planners x agent counts x seeds with gdrhcr_sim on Dask
distributed, into one tidy CSV. Each run is one Dask task; the CSV is written by this process
(the client) only, one whole flushed line per finished run. Stop it any time (Ctrl-C, kill);
run it again with the same arguments and it resumes: finished runs are skipped, failed ones
retried. A worker that dies mid-run loses nothing: the scheduler runs its task elsewhere.

    tools/gdrhcr_sweep.py config/experiments/smoke.yaml --out results/smoke.csv --jobs 2
    tools/gdrhcr_sweep.py config/experiments/smoke.yaml --out results/smoke.csv \\
        --scheduler tcp://head-node:8786

Without --scheduler a local cluster of --jobs single-threaded workers runs in this process.
With --scheduler the runs go to that cluster's workers (started with dask-worker; see
docs/distributed.md). Workers must find the simulator and the maps at the same absolute paths
as here (a shared file system, or a checkout built at the same path on every worker), or under
--worker-root; this is checked on every worker before the first run, and a worker whose
simulator or maps differ from this machine's is named in a warning. Every row records the
`worker` that ran it and its `host`.

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
A planner entry may carry `agents: [...]` to run that planner on fewer agent counts.
"""
import argparse
import csv
import hashlib
import json
import math
import os
import socket
import subprocess
import sys
import tempfile
import time
import uuid

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))

KEY = ["label", "map", "tasks", "agents", "seed", "steps"]
FIELDS = KEY + [
    "sweep", "planner", "params", "throughput", "goals_reached", "free_flow_throughput",
    "collisions", "plan_time_mean_s", "plan_time_max_s", "planned_steps", "step_wall_time_mean_s",
    "wall_time_s", "groups_mean_count", "groups_mean_size", "groups_mean_max_size",
    "groups_replanned_per_step", "cache_reuses", "threshold_fallbacks", "failure_fallbacks",
    "solver_calls", "solver_failures", "status", "error", "worker", "host",
]


class ConfigError(Exception):
    pass


class SweepError(Exception):
    """A problem that stops the sweep before it starts (exit code 2), with its reason."""


def load_config(path):
    with open(path) as f:
        cfg = yaml.safe_load(f)
    if not isinstance(cfg, dict) or not isinstance(cfg.get("experiments"), list):
        raise ConfigError("%s: expected a mapping with an 'experiments' list" % path)
    return cfg


def expand(cfg):
    """All runs of a config, as dicts with the KEY fields and the sim options."""
    steps = int(cfg.get("steps", 500))
    seeds = cfg.get("seeds", 1)
    seeds = list(range(int(seeds))) if isinstance(seeds, int) else [int(s) for s in seeds]
    runs = []
    for e, exp in enumerate(cfg["experiments"]):
        if not isinstance(exp, dict):
            raise ConfigError("experiment %d: expected a mapping" % e)
        for field in ("map", "agents", "planners"):
            if field not in exp:
                raise ConfigError("experiment %d: missing '%s'" % (e, field))
        tasks = exp.get("tasks", "random")
        for p in exp["planners"]:
            if not isinstance(p, dict):
                raise ConfigError("experiment %d: a planner entry must be a mapping, got %r" % (e, p))
            p = dict(p)
            label = str(p.pop("label", p.get("planner", "pibt")))
            frac = p.pop("k_threshold_fraction", None)
            cap = p.pop("k_threshold_cap", None)
            agent_counts = p.pop("agents", exp["agents"])
            for agents in agent_counts:
                opts = dict(p)
                if frac is not None:
                    opts["k-threshold"] = max(2, min(int(math.floor(frac * agents)), int(cap or 20)))
                for seed in seeds:
                    runs.append({"label": label, "map": exp["map"], "tasks": tasks,
                                 "agents": int(agents), "seed": seed, "steps": steps,
                                 "options": opts})
    return runs


def select(runs, args):
    """The runs --labels, --maps and --agents keep; naming something the config lacks is an error."""
    def wanted(opt, have):
        if not opt:
            return None
        want = {x.strip() for x in opt.split(",") if x.strip()}
        unknown = sorted(want - have)
        if unknown:
            raise ConfigError("%s not in the config (it has %s)" % (", ".join(unknown), ", ".join(sorted(have))))
        return want
    mapname = lambda r: os.path.splitext(os.path.basename(r["map"]))[0]
    labels = wanted(args.labels, {r["label"] for r in runs})
    maps = wanted(args.maps, {mapname(r) for r in runs})
    agents = wanted(args.agents, {str(r["agents"]) for r in runs})
    return [r for r in runs if (labels is None or r["label"] in labels) and (maps is None or mapname(r) in maps)
            and (agents is None or str(r["agents"]) in agents)]


def run_key(row):
    return tuple(str(row[k]) for k in KEY)


def read_csv(path):
    """Rows of an existing sweep CSV (drops a torn last line left by a kill, and upgrades a CSV
    written before the worker/host columns existed)."""
    if not os.path.exists(path) or os.path.getsize(path) == 0:
        return []
    with open(path, newline="") as f:
        text = f.read()
    if not text.endswith("\n"):
        text = text[: text.rfind("\n") + 1]
    reader = csv.DictReader(text.splitlines())
    header = reader.fieldnames or []
    unknown = [h for h in header if h not in FIELDS]
    if unknown or any(k not in header for k in KEY + ["status"]):
        raise SweepError("%s is not a gdrhcr_sweep CSV (unknown columns %s); choose another --out"
                         % (path, ", ".join(unknown) or "none, but key columns missing"))
    rows = []
    for r in reader:
        if None in r or any(r.get(h) is None for h in header):
            continue  # a line with too many or too few fields
        rows.append({k: r.get(k, "") for k in FIELDS})
    return rows


def rewrite(path, rows):
    tmp = path + ".tmp"
    with open(tmp, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS)
        w.writeheader()
        w.writerows(rows)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def prepare_csv(path):
    """Keys of the finished runs; rewrites the CSV keeping only them (one row per key), so failed
    runs are retried."""
    rows = read_csv(path)
    kept, done = [], set()
    for r in rows:
        if r["status"] == "ok" and run_key(r) not in done:
            kept.append(r)
            done.add(run_key(r))
    if os.path.exists(path):
        rewrite(path, kept)
    return done


# ---- what runs on a worker (pickled by value: workers need not have tools/ on their path) ----

def _pdeathsig():
    """A preexec_fn making the child die with the worker that started it (Linux
    PR_SET_PDEATHSIG), or None. libc is loaded here, in the parent: loading a library in the
    forked child of a threaded process can crash it."""
    try:
        import ctypes
        import signal
        prctl = ctypes.CDLL("libc.so.6", use_errno=True).prctl
        prctl.argtypes = [ctypes.c_int, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong]
        prctl.restype = ctypes.c_int
    except Exception:
        return None
    sig = int(signal.SIGKILL)
    return lambda: prctl(1, sig, 0, 0, 0)


def _task_cancelled():
    """True when the scheduler no longer wants the task this thread runs (its client left)."""
    try:
        from distributed import get_worker
        from distributed.worker import thread_state
        ts = get_worker().state.tasks.get(thread_state.key)
        return ts is None or ts.state in ("cancelled", "released", "forgotten")
    except Exception:
        return False


def _this_worker():
    try:
        from distributed import get_worker
        w = get_worker()
        name = w.name
        return str(name) if name is not None and str(name) != w.address else w.address
    except Exception:
        return ""


def execute(sim, run, root=ROOT):
    """One run of gdrhcr_sim; returns its CSV row (never raises for a failed run)."""
    row = {k: run[k] for k in KEY}
    row["planner"] = run["options"].get("planner", "pibt")
    row["worker"] = _this_worker()
    row["host"] = socket.gethostname()
    mp = run["map"] if os.path.isabs(run["map"]) else os.path.join(root, run["map"])
    for what, path in (("simulator", sim), ("map", mp)):
        if not os.path.exists(path):
            row.update(status="error", error="%s not found on worker %s (host %s): %s"
                       % (what, row["worker"] or "local", row["host"], path))
            return row
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "r.json")
        cmd = [sim, "--map", mp, "--tasks", run["tasks"], "--agents", str(run["agents"]),
               "--seed", str(run["seed"]), "--steps", str(run["steps"]), "--out", out, "--quiet"]
        for k, v in run["options"].items():
            cmd += ["--" + str(k), str(v)]
        with open(os.path.join(tmp, "err"), "w+") as err:
            proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err,
                                    preexec_fn=_pdeathsig())
            while True:
                try:
                    rc = proc.wait(timeout=1.0)
                    break
                except subprocess.TimeoutExpired:
                    if _task_cancelled():
                        proc.kill()
                        proc.wait()
                        row.update(status="error", error="cancelled (the client left)")
                        return row
            err.seek(0)
            stderr = err.read()
        if rc != 0:
            row["status"] = "collision" if rc == 3 else "error"
            row["error"] = (stderr.strip().replace("\n", " ") or "exit code %d" % rc)[:500]
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


def _sha256(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def check_files(sim, maps):
    """Run on each worker at start: problems with the simulator and maps, and their hashes."""
    problems, hashes = [], {}
    if not os.path.isfile(sim) or not os.access(sim, os.X_OK):
        problems.append("simulator %s is missing or not executable" % sim)
    else:
        try:
            p = subprocess.run([sim, "--help"], capture_output=True, text=True, timeout=60)
            if "--map" not in p.stdout + p.stderr:
                problems.append("simulator %s does not run as gdrhcr_sim (--help printed no --map)" % sim)
        except (OSError, subprocess.SubprocessError) as e:
            problems.append("simulator %s does not run: %s" % (sim, e))
        hashes[sim] = _sha256(sim) if os.path.isfile(sim) else ""
    for m in maps:
        if not os.path.isfile(m):
            problems.append("map %s is missing" % m)
        else:
            hashes[m] = _sha256(m)
    return {"host": socket.gethostname(), "problems": problems, "hashes": hashes}


async def check_files_async(sim, maps):
    """check_files off the worker's event loop (client.run runs coroutines there)."""
    import asyncio
    return await asyncio.get_running_loop().run_in_executor(None, check_files, sim, maps)


# ---- the client ----

def worker_path(path, worker_root):
    """Where a file of this checkout is on the workers (--worker-root), else the same path."""
    path = os.path.abspath(path)
    if worker_root and (path + os.sep).startswith(ROOT + os.sep):
        return os.path.join(worker_root, os.path.relpath(path, ROOT))
    return path


def connect(args):
    """A distributed Client: to --scheduler, or to a local in-process cluster of --jobs workers."""
    import logging
    try:
        from distributed import Client, LocalCluster
    except ImportError as e:
        raise SweepError("Dask distributed is not installed (%s): apt-get install python3-distributed "
                         "python3-dask, or run scripts/install_deps.sh" % e)
    if __name__ != "__main__":  # imported (tests, other tools): ship this module's code by value
        import cloudpickle
        cloudpickle.register_pickle_by_value(sys.modules[__name__])
    if args.scheduler:
        try:
            client = Client(args.scheduler, timeout=args.connect_timeout)
        except (OSError, TimeoutError, ValueError) as e:
            raise SweepError("cannot reach the Dask scheduler at %s within %g s: %s"
                             % (args.scheduler, args.connect_timeout, e))
        try:
            client.wait_for_workers(1, timeout=args.connect_timeout)
        except (OSError, TimeoutError) as e:
            client.close()
            raise SweepError("the Dask scheduler at %s has no workers (waited %g s); start some with "
                             "dask-worker %s (docs/distributed.md)" % (args.scheduler, args.connect_timeout, args.scheduler))
        return client, None
    # Threads, not processes: each task only waits on a gdrhcr_sim subprocess, and a killed
    # client then takes its workers (and, through PR_SET_PDEATHSIG, their runs) with it.
    cluster = LocalCluster(n_workers=args.jobs, threads_per_worker=1, processes=False,
                           dashboard_address=":0", silence_logs=logging.ERROR)
    return Client(cluster), cluster


def check_workers(client, sim, maps, local_sim, local_maps):
    """Every connected worker must find and run the simulator and find every map."""
    try:
        reports = client.run(check_files_async, sim, maps, on_error="return")
    except Exception as e:
        raise SweepError("checking the workers failed: %s" % e)
    if not reports:
        raise SweepError("no Dask workers to run on")
    names = {a: str(w.get("name", a)) for a, w in client.scheduler_info().get("workers", {}).items()}
    bad = []
    for addr, r in sorted(reports.items()):
        if isinstance(r, BaseException):
            bad.append("worker %s: the check failed: %s: %s" % (names.get(addr, addr), type(r).__name__, r))
        elif r["problems"]:
            bad.append("worker %s (host %s): %s" % (names.get(addr, addr), r["host"], "; ".join(r["problems"])))
    if bad:
        raise SweepError("workers cannot run the sweep (they need the simulator and maps at the same "
                         "paths, via a shared file system or a build on each worker, or --worker-root; "
                         "see docs/distributed.md):\n  " + "\n  ".join(bad))
    mine = {w: _sha256(l) for w, l in zip([sim] + list(maps), [local_sim] + list(local_maps))
            if os.path.isfile(l)}
    for addr, r in sorted(reports.items()):
        differ = [os.path.basename(p) for p, h in r["hashes"].items() if p in mine and h != mine[p]]
        if differ:
            print("gdrhcr_sweep: warning: worker %s (host %s) has a different %s than this machine; "
                  "its rows may differ" % (names.get(addr, addr), r["host"], ", ".join(differ)), file=sys.stderr)
    return reports


def worker_label(row, local):
    """The worker column: dask-worker's --name (else its address); local-N on a local cluster."""
    if local and row.get("worker", "") != "":
        return "local-%s" % row["worker"]
    return row.get("worker", "")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("config")
    ap.add_argument("--out", required=True, help="the CSV (created or resumed)")
    ap.add_argument("--jobs", type=int, default=max(1, (os.cpu_count() or 2)),
                    help="workers of the local cluster (ignored with --scheduler)")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler, e.g. tcp://head:8786 "
                    "(default: a local cluster of --jobs workers)")
    ap.add_argument("--worker-root", help="where this checkout is on the workers, when not at the same "
                    "path (the simulator and maps are taken from there)")
    ap.add_argument("--connect-timeout", type=float, default=30.0,
                    help="seconds to wait for the scheduler and a first worker (default 30)")
    ap.add_argument("--sim", help="gdrhcr_sim binary (default: config 'sim' or build/src/gdrhcr_sim)")
    ap.add_argument("--limit", type=int, default=0, help="run at most this many new runs (0 = all)")
    sel = ap.add_argument_group("selecting part of a config (the CSV keeps accumulating: run the rest later)")
    sel.add_argument("--seeds", help="override the config's seeds: a count N (seeds 0..N-1) or a list 3,4,5")
    sel.add_argument("--labels", help="only these planner labels (comma-separated)")
    sel.add_argument("--maps", help="only these maps (comma-separated names, e.g. warehouse-10-20-10-2-1)")
    sel.add_argument("--agents", help="only these agent counts (comma-separated)")
    args = ap.parse_args(argv)
    if args.jobs < 1:
        ap.error("--jobs must be at least 1")
    try:
        cfg = load_config(args.config)
        if args.seeds:
            cfg["seeds"] = int(args.seeds) if args.seeds.isdigit() else [int(x) for x in args.seeds.split(",")]
        runs = select(expand(cfg), args)
    except (OSError, yaml.YAMLError, ConfigError, ValueError, TypeError) as e:
        print("gdrhcr_sweep: bad config: %s" % e, file=sys.stderr)
        return 2
    sim = args.sim or cfg.get("sim") or os.path.join(ROOT, "build", "src", "gdrhcr_sim")
    if not os.path.isabs(sim):
        sim = os.path.join(ROOT, sim)
    if not args.worker_root and not os.access(sim, os.X_OK):
        print("gdrhcr_sweep: simulator not found at %s (build it with scripts/build_core.sh)" % sim, file=sys.stderr)
        return 2
    local_maps = sorted({r["map"] if os.path.isabs(r["map"]) else os.path.join(ROOT, r["map"]) for r in runs})
    missing = [m for m in local_maps if not os.path.isfile(m)]
    if missing and not args.worker_root:
        print("gdrhcr_sweep: bad config: map not found: %s" % ", ".join(missing), file=sys.stderr)
        return 2
    client = cluster = None
    try:
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        done = prepare_csv(args.out)
        todo = [r for r in runs if run_key(r) not in done]
        n_done = len(runs) - len(todo)
        if args.limit:
            todo = todo[: args.limit]
        client, cluster = connect(args)
        local = cluster is not None
        wsim = worker_path(sim, args.worker_root)
        wroot = args.worker_root or ROOT
        wmaps = [worker_path(m, args.worker_root) for m in local_maps]
        if todo:
            check_workers(client, wsim, wmaps, sim, local_maps)
        nworkers = len(client.scheduler_info().get("workers", {}))
        where = ("a local cluster of %d workers" % args.jobs) if local else \
            ("%s (%d workers now)" % (args.scheduler, nworkers))
        print("gdrhcr_sweep: %d runs selected, %d already done, %d to run on %s"
              % (len(runs), n_done, len(todo), where), flush=True)
        return sweep(client, cfg, args, todo, wsim, wroot, local)
    except SweepError as e:
        print("gdrhcr_sweep: %s" % e, file=sys.stderr)
        return 2
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()


def sweep(client, cfg, args, todo, sim, root, local):
    from distributed import as_completed
    from concurrent.futures import CancelledError
    name = cfg.get("name", os.path.basename(args.config))
    new_file = not os.path.exists(args.out) or os.path.getsize(args.out) == 0
    failures = 0
    t0 = time.time()
    with open(args.out, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        if new_file:
            writer.writeheader()
            f.flush()
        futures = {}
        for r in todo:
            key = "gdrhcr_sim-%s-%s-a%d-s%d-%s" % (r["label"], os.path.basename(r["map"]), r["agents"],
                                                 r["seed"], uuid.uuid4().hex[:12])
            fut = client.submit(execute, sim, r, root, key=key, pure=False)
            futures[fut] = r
        for k, fut in enumerate(as_completed(futures), 1):
            run = futures[fut]
            try:
                row = fut.result()
            except (Exception, CancelledError) as e:  # e.g. KilledWorker: its workers kept dying
                row = {kk: run[kk] for kk in KEY}
                row.update(planner=run["options"].get("planner", "pibt"), status="error",
                           error=("%s: %s" % (type(e).__name__, e)).replace("\n", " ")[:500])
            row["sweep"] = name
            row["worker"] = worker_label(row, local)
            writer.writerow(row)  # one whole line per run, flushed: a kill tears at most one
            f.flush()
            os.fsync(f.fileno())
            elapsed = time.time() - t0
            eta = elapsed / k * (len(todo) - k)
            if row["status"] != "ok":
                failures += 1
            summary = ("throughput %.3f" % row["throughput"]) if row["status"] == "ok" else row["status"] + ": " + row["error"][:120]
            print("[%d/%d] %s %s agents=%s seed=%s on %s: %s | elapsed %ds, ETA %ds"
                  % (k, len(todo), row["label"], os.path.basename(row["map"]), row["agents"],
                     row["seed"], row.get("worker") or "?", summary, elapsed, eta), flush=True)
    print("gdrhcr_sweep: finished, %d failed runs (kept with their status; rerun to retry)" % failures)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
