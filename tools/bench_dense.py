#!/usr/bin/env python3
"""Dense-fleet benchmark against LLLG (issue 11). Prints figures; it is not a test.

Runs GD-RHCR (the product default and `--preset paper`) and PIBT on the settings of LLLG's
recorded figures (Arita & Okumura, "Lifelong LaCAM with Local Guidance", SoCS-26, run with its
README's settings `--lg --lg_window 20 --lacam_horizon 10`, 1 s per step, on a 2-core machine
like ours), random goals, 500 steps, seed 1, and prints throughput, ms per step (wall and CPU)
and the ratios to LLLG's figures. Also warehouse-10-20-10-2-1 MAPD at 800 agents (the paper
reports GD-RHCR +57.7% over PIBT there). `--ablation` adds PIBT's techniques one at a time.

    /usr/bin/python3 tools/bench_dense.py [--sim build/src/gdrhcr_sim] [--steps 500] [--seed 1]
        [--ablation] [--more] [--json results/dense_vs_lllg.json]

Time per step: `wall` is the planner's wall time per step (the product metric; noisy on a shared
machine), `cpu` its process CPU time per step (all threads), steadier under load. The LLLG
budget column is a tenth of LLLG's time per step, the issue's target.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

TOP = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# LLLG's figures (issue 11's table): (map, agents) -> (throughput, ms per step).
LLLG = {
    ("warehouse-10-20-10-2-1", 400): (4.01, 63.0),
    ("warehouse-10-20-10-2-1", 800): (7.34, 149.0),
    ("random-32-32-20", 300): (9.44, 72.0),
    ("empty-48-48", 400): (12.06, 41.0),
}
PLANNERS = [
    ("GD-RHCR", ["--planner", "gd-rhcr"]),
    ("GD-RHCR paper", ["--planner", "gd-rhcr", "--preset", "paper"]),
    ("PIBT", ["--planner", "pibt"]),
]
ABLATION = [
    ("PIBT plain (no reset, no swap: before issue 11)", ["--planner", "pibt", "--priority-reset", "0", "--swap", "0"]),
    ("PIBT + priority reset", ["--planner", "pibt", "--swap", "0"]),
    ("PIBT + swap", ["--planner", "pibt", "--priority-reset", "0"]),
    ("PIBT + reset + swap (our PIBT)", ["--planner", "pibt"]),
    ("PIBT + reset + swap, random tie-break", ["--planner", "pibt", "--tie-break", "random"]),
    ("PIBT + local guidance, lazy", ["--planner", "pibt", "--guidance", "local", "--lg-lazy", "1"]),
    ("PIBT + local guidance, keep provably optimal paths", ["--planner", "pibt", "--guidance", "local", "--lg-keep-optimal", "1"]),
    ("PIBT + local guidance (every step)", ["--planner", "pibt", "--guidance", "local"]),
    ("GD-RHCR paper + swap", ["--planner", "gd-rhcr", "--preset", "paper", "--swap", "1"]),
    ("GD-RHCR default without the density rule", ["--planner", "gd-rhcr", "--max-density", "1"]),
    ("GD-RHCR default, guided PIBT for every group", ["--planner", "gd-rhcr", "--solver", "pibt"]),
    ("PIBT + local guidance + motion forecast (8 steps)", ["--planner", "pibt", "--guidance", "local", "--lg-forecast", "8"]),
    ("GD-RHCR default, no motion forecast", ["--planner", "gd-rhcr", "--lg-forecast", "0"]),
    ("GD-RHCR default, motion forecast (8 steps) on every map", ["--planner", "gd-rhcr", "--lg-forecast", "8"]),
]


def run(sim, map_name, agents, args, steps, seed, tasks="random"):
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        out = f.name
    cmd = [sim, "--map", os.path.join(TOP, "maps", map_name + ".map"), "--tasks", tasks, "--agents", str(agents),
           "--steps", str(steps), "--seed", str(seed), "--quiet", "--out", out] + args
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    with open(out) as f:
        d = json.load(f)
    os.unlink(out)
    return {
        "map": map_name, "agents": agents, "tasks": tasks, "steps": steps, "seed": seed,
        "args": args, "throughput": d["throughput"], "free_flow": d["free_flow_throughput"],
        "wall_ms": 1000 * d["step_wall_time_mean_s"], "cpu_ms": 1000 * d["step_cpu_time_mean_s"],
        "agents_late": d["progress"]["agents_late"], "late_at_end": d["progress"]["late_at_end"],
        "longest_wait": d["progress"]["longest_wait_steps"], "params": d.get("params", {}),
    }


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sim", default=os.environ.get("GDRHCR_SIM", os.path.join(TOP, "build/src/gdrhcr_sim")))
    ap.add_argument("--steps", type=int, default=500)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--ablation", action="store_true", help="also PIBT's techniques one at a time")
    ap.add_argument("--no-mapd", action="store_true", help="skip the MAPD comparison")
    ap.add_argument("--json", help="write every row here")
    ap.add_argument("--plot", help="draw throughput and ms per step against LLLG's into this PNG")
    ap.add_argument("--from-json", help="do not run: plot (--plot) the rows of an earlier --json")
    args = ap.parse_args(argv)
    if args.from_json:
        with open(args.from_json) as f:
            plot(json.load(f)["rows"], args.plot or "dense_vs_lllg.png")
        return
    if not os.access(args.sim, os.X_OK):
        sys.exit(f"bench_dense: simulator {args.sim} not found or not executable (build it: bash scripts/build_core.sh)")
    rows = []
    print(f"# Dense fleets against LLLG: random goals, {args.steps} steps, seed {args.seed}\n")
    print("| map | agents | planner | throughput | vs LLLG | wall ms/step | cpu ms/step | LLLG ms/step / 10 | free flow | agents late | longest wait |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for (m, a), (tp, ms) in LLLG.items():
        for label, pargs in PLANNERS:
            r = run(args.sim, m, a, pargs, args.steps, args.seed)
            r["planner"] = label
            r["lllg_throughput"], r["lllg_ms"] = tp, ms
            rows.append(r)
            ok_t = "" if r["throughput"] >= tp else " (below)"
            ok_ms = "" if r["wall_ms"] <= ms / 10 else " (over)"
            print(f"| {m} | {a} | {label} | {r['throughput']:.2f} | {100 * r['throughput'] / tp:.0f}%{ok_t} | "
                  f"{r['wall_ms']:.2f}{ok_ms} | {r['cpu_ms']:.2f} | {ms / 10:.1f} | {r['free_flow']:.2f} | "
                  f"{r['agents_late']} | {r['longest_wait']} |", flush=True)
    if not args.no_mapd:
        print("\n# MAPD, warehouse-10-20-10-2-1, 800 agents (paper: GD-RHCR +57.7% over PIBT)\n")
        print("| planner | throughput | vs PIBT | wall ms/step | cpu ms/step |")
        print("|---|---|---|---|---|")
        mapd = {}
        for label, pargs in PLANNERS:
            r = run(args.sim, "warehouse-10-20-10-2-1", 800, pargs, args.steps, args.seed, tasks="mapd")
            r["planner"] = label
            rows.append(r)
            mapd[label] = r
        for label, r in mapd.items():
            print(f"| {label} | {r['throughput']:.2f} | {100 * (r['throughput'] / mapd['PIBT']['throughput'] - 1):+.1f}% | "
                  f"{r['wall_ms']:.2f} | {r['cpu_ms']:.2f} |")
    if args.ablation:
        print("\n# Ablation: each technique alone (throughput; cpu ms/step)\n")
        keys = list(LLLG)
        print("| variant | " + " | ".join(f"{m} {a}" for m, a in keys) + " |")
        print("|---|" + "---|" * len(keys))
        for label, pargs in ABLATION:
            cells = []
            for m, a in keys:
                r = run(args.sim, m, a, pargs, args.steps, args.seed)
                r["planner"] = label
                rows.append(r)
                cells.append(f"{r['throughput']:.2f}; {r['cpu_ms']:.2f}")
            print(f"| {label} | " + " | ".join(cells) + " |", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rows": rows, "lllg": [{"map": m, "agents": a, "throughput": t, "ms_per_step": ms}
                                              for (m, a), (t, ms) in LLLG.items()]}, f, indent=1)
        print(f"\nwrote {args.json}")
    if args.plot:
        plot(rows, args.plot)


def plot(rows, path):
    """Bars per setting: throughput (left) and wall and CPU ms per step (right, log), LLLG marked."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = list(LLLG)
    labels = [label for label, _ in PLANNERS]
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12, 4.2))
    width = 0.8 / len(labels)
    for k, label in enumerate(labels):
        tp, wall, cpu = [], [], []
        for m, a in keys:
            r = next((r for r in rows if r["map"] == m and r["agents"] == a and r.get("planner") == label
                      and r.get("tasks", "random") == "random"), None)
            tp.append(r["throughput"] if r else 0)
            wall.append(r["wall_ms"] if r else 0)
            cpu.append(r["cpu_ms"] if r else 0)
        xs = [i + (k - (len(labels) - 1) / 2) * width for i in range(len(keys))]
        ax1.bar(xs, tp, width, label=label)
        ax2.bar(xs, wall, width, label=label + " (wall)")
        ax2.scatter(xs, cpu, marker="_", s=200, color="black", zorder=3, label=None if k else "CPU time")
    for i, key in enumerate(keys):
        ax1.hlines(LLLG[key][0], i - 0.45, i + 0.45, colors="red", linestyles="--", label="LLLG" if i == 0 else None)
        ax2.hlines(LLLG[key][1] / 10, i - 0.45, i + 0.45, colors="red", linestyles="--",
                   label="LLLG / 10" if i == 0 else None)
    names = [f"{m.replace('10-20-10-2-', '')}\n{a} agents" for m, a in keys]
    for ax in (ax1, ax2):
        ax.set_xticks(range(len(keys)))
        ax.set_xticklabels(names, fontsize=8)
    ax1.set_ylabel("throughput (goals / step)")
    ax2.set_ylabel("ms per step")
    ax2.set_yscale("log")
    ax1.legend(fontsize=8)
    ax2.legend(fontsize=8)
    ax1.set_title("throughput, random goals, 500 steps, seed 1")
    ax2.set_title("time per step (target: a tenth of LLLG's)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
