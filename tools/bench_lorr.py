#!/usr/bin/env python3
"""Errands against the time budget on LoRR instances, refereed by the Start-Kit (issue 24).
Prints figures; it is not a test.

For every instance and every budget it runs `scripts/bench_lorr.sh START_KIT INSTANCE STEPS OUT
BUDGET_MS` (the Start-Kit's own simulator, our planner as its MAPFPlanner) and reads back the
Start-Kit's output (numTaskFinished, AllValid, errors, plannerTimes) and our own time per step
(the adapter's clock, OUT.times). It prints, per instance, the errands at each budget against the
best-known, with the mean, p99 and max ms per step we used, and where each errand's steps went,
from the Start-Kit's own paths and events: forward moves, turns and waits per finished task (the
first task of each agent includes the warm-up). It writes everything to a JSON file and plots
errands against the budget (matplotlib; without it the plot is skipped, with a note).

    /usr/bin/python3 tools/bench_lorr.py [--start-kit DIR] [--budgets 10 30 100 300 1000]
        [--steps N] [--out-dir DIR] [--json FILE] [--plot FILE.png] INSTANCE.json ...

STEPS: --steps, else the main round's own length for the instances it knows (MR23-I-03 500, ...).
Our planner's settings come from the environment as for bench_lorr.sh (GDRHCR_PLANNER,
GDRHCR_PARAMS, GDRHCR_TURNS, GDRHCR_SEED). The offline preparation (GDRHCR_PREP_DIR, made in the
first run's preprocessing phase and loaded by the later ones) is cached in --prep-dir (default
build/lorr/prep; "none": no preparation).
"""
import argparse
import json
import os
import re
import subprocess
import sys

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The League of Robot Runners 2023 main round: (steps, best-known errands, rotation, 1 s per step).
MAIN_ROUND_2023 = {
    "MR23-I-03": (500, 3042),
    "MR23-I-05": (1000, 7432),
    "MR23-I-08": (2000, 6059),
    "MR23-I-02": (3500, 49186),
    "MR23-I-10": (5000, 194677),
}


def default_start_kit():
    for c in (os.path.join(TOP, "..", "shared", "lorr", "start-kit-v1.1.5"), "/work/shared/lorr/start-kit-v1.1.5"):
        if os.path.isfile(os.path.join(c, "src", "driver.cpp")):
            return c
    return None


def percentile(values, q):
    if not values:
        return float("nan")
    s = sorted(values)
    return s[min(len(s) - 1, int(q * len(s)))]


def errand_steps(output):
    """Per task the Start-Kit counts finished: the agent's actions from its assignment to its
    finish (actualPaths and events of the Start-Kit's output), summed: forward moves (F), turns
    (R, C) and waits (W, and the Start-Kit's own T for a step without a valid plan)."""
    sums = {"errands": 0, "steps": 0, "forward": 0, "turns": 0, "waits": 0}
    for path, events in zip(output.get("actualPaths", []), output.get("events", [])):
        actions = path.split(",") if path else []
        assigned = {}
        for task, t, kind in events:
            if kind == "assigned":
                assigned[task] = t
            elif kind == "finished" and task in assigned:
                leg = actions[assigned.pop(task):t]
                sums["errands"] += 1
                sums["steps"] += len(leg)
                sums["forward"] += leg.count("F")
                sums["turns"] += leg.count("R") + leg.count("C")
                sums["waits"] += len(leg) - leg.count("F") - leg.count("R") - leg.count("C")
    n = max(1, sums["errands"])
    return {"errands": sums["errands"], **{f"{k}_per_errand": sums[k] / n for k in ("steps", "forward", "turns", "waits")}}


def run_one(kit, instance, steps, budget, out_dir):
    """One bench_lorr.sh run; returns its row (errands, validity, our and the Start-Kit's ms)."""
    name = os.path.splitext(os.path.basename(instance))[0]
    out = os.path.join(out_dir, f"{name}-{budget:g}ms.json")
    cmd = ["bash", os.path.join(TOP, "scripts", "bench_lorr.sh"), kit, instance, str(steps), out, f"{budget:g}"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"bench_lorr.sh failed on {instance} at {budget:g} ms:\n{proc.stderr[-2000:]}")
    with open(out) as f:
        r = json.load(f)
    with open(out[: -len(".json")] + ".times") as f:
        ours = [float(x) for x in f.read().split()]
    kit_ms = [1000 * t for t in r.get("plannerTimes", [])]
    prep = re.search(r"traffic-cost (\S+) from the preparation", proc.stderr)
    stats = re.findall(r"planner stats (\{.*\})", proc.stderr)  # the adapter's, every 500 steps
    return {
        "planner_stats": json.loads(stats[-1]) if stats else None,
        "prep_traffic_cost": float(prep.group(1)) if prep else None,
        "instance": name, "steps": steps, "budget_ms": budget, "errands": r["numTaskFinished"],
        "all_valid": r["AllValid"], "errors": len(r.get("errors", [])),
        "ms_mean": sum(ours) / len(ours) if ours else float("nan"), "ms_p99": percentile(ours, 0.99),
        "ms_max": max(ours, default=float("nan")), "start_kit_ms_mean": sum(kit_ms) / len(kit_ms) if kit_ms else float("nan"),
        "start_kit_ms_max": max(kit_ms, default=float("nan")), "output": out, "command": " ".join(cmd),
        "errand_steps": errand_steps(r),
    }


def plot(rows, path):
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print(f"bench_lorr: matplotlib is not installed (Debian: python3-matplotlib); no plot at {path}")
        return False
    fig, ax = plt.subplots(figsize=(6, 4))
    for name in dict.fromkeys(r["instance"] for r in rows):
        mine = [r for r in rows if r["instance"] == name]
        best = mine[0].get("best_known")
        ax.plot([r["budget_ms"] for r in mine], [r["errands"] / best if best else r["errands"] for r in mine],
                marker="o", label=name)
    ax.set_xscale("log")
    ax.set_xlabel("budget per step (ms)")
    ax.set_ylabel("errands / best-known")
    ax.axhline(1.0, color="grey", linestyle="--", linewidth=1)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)
    return True


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("instances", nargs="+", help="LoRR problem JSON files")
    ap.add_argument("--start-kit", default=default_start_kit(), help="the LoRR Start-Kit v1.1.5 directory")
    ap.add_argument("--budgets", nargs="+", type=float, default=[10, 30, 100, 300, 1000], help="ms per step")
    ap.add_argument("--steps", type=int, help="timesteps (default: the main round's length)")
    ap.add_argument("--out-dir", default=os.path.join(TOP, "results", "lorr"), help="the Start-Kit outputs")
    ap.add_argument("--json", help="write every row here")
    ap.add_argument("--plot", help="errands / best-known against the budget, PNG")
    ap.add_argument("--prep-dir", default=os.path.join(TOP, "build", "lorr", "prep"),
                    help="the offline preparation's cache (GDRHCR_PREP_DIR); none = no preparation")
    a = ap.parse_args(argv)
    if not a.start_kit or not os.path.isfile(os.path.join(a.start_kit, "src", "driver.cpp")):
        ap.error(f"--start-kit {a.start_kit} is not a LoRR Start-Kit (no src/driver.cpp)")
    if any(b <= 0 for b in a.budgets):
        ap.error("--budgets must be positive ms")
    if a.steps is not None and a.steps < 1:
        ap.error("--steps must be at least 1")
    os.makedirs(a.out_dir, exist_ok=True)
    if a.prep_dir != "none":
        os.makedirs(a.prep_dir, exist_ok=True)
        os.environ["GDRHCR_PREP_DIR"] = os.path.abspath(a.prep_dir)
    rows = []
    print(f"{'instance':<12} {'steps':>5} {'budget ms':>9} {'errands':>8} {'best-known':>10} {'share':>6} "
          f"{'valid':>5} {'mean ms':>8} {'p99 ms':>7} {'max ms':>7}")
    for instance in a.instances:
        if not os.path.isfile(instance):
            ap.error(f"no instance file {instance}")
        name = os.path.splitext(os.path.basename(instance))[0]
        known = MAIN_ROUND_2023.get(name)
        steps = a.steps or (known[0] if known else None)
        if steps is None:
            ap.error(f"{name} is not a main-round instance this tool knows; give --steps")
        best = known[1] if known and steps == known[0] else None  # best-known only at full length
        for budget in a.budgets:
            row = run_one(a.start_kit, instance, steps, budget, a.out_dir)
            row["best_known"] = best
            rows.append(row)
            share = f"{row['errands'] / best:.1%}" if best else "-"
            print(f"{name:<12} {steps:>5} {budget:>9g} {row['errands']:>8} {best or '-':>10} {share:>6} "
                  f"{row['all_valid']:>5} {row['ms_mean']:>8.1f} {row['ms_p99']:>7.1f} {row['ms_max']:>7.1f}",
                  flush=True)
            e = row["errand_steps"]
            print(f"{'':<12} per errand: {e['steps_per_errand']:.1f} steps = {e['forward_per_errand']:.1f} forward"
                  f" + {e['turns_per_errand']:.1f} turns + {e['waits_per_errand']:.1f} waits", flush=True)
            ps = row["planner_stats"] or {}
            if "secondary_operation_calls" in ps and ps.get("steps_with_a_solve"):
                print(f"{'':<12} PIBT over operations at {ps['secondary_operation_calls']} of "
                      f"{ps['steps_with_a_solve']} steps with a solve (to the last stats line)", flush=True)
    if a.json:
        os.makedirs(os.path.dirname(os.path.abspath(a.json)), exist_ok=True)
        with open(a.json, "w") as f:
            json.dump({"rows": rows, "planner": os.environ.get("GDRHCR_PLANNER", "gd-rhcr"),
                       "params": os.environ.get("GDRHCR_PARAMS", ""),
                       "prep_dir": os.environ.get("GDRHCR_PREP_DIR", "")}, f, indent=1)
    if a.plot:
        plot(rows, a.plot)
    invalid = [r for r in rows if r["all_valid"] != "Yes" or r["errors"]]
    for r in invalid:
        print(f"bench_lorr: INVALID run {r['instance']} at {r['budget_ms']:g} ms: {r['output']}", file=sys.stderr)
    return 1 if invalid else 0


if __name__ == "__main__":
    sys.exit(main())
