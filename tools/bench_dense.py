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

Like for like (`--shared`): LLLG draws its own task stream (its own random starts; a new goal
is any free cell other than the others' current goals), so its figure and ours come from
different streams, whose free-flow bounds differ by a few percent from seed to seed. `--shared`
writes one instance per (map, agents, seed): distinct random starts and, per agent, a fixed
sequence of random goals (any free cell but the previous one), as a LoRR problem for gdrhcr_sim
(`roundrobin`: agent k's j-th task is tasks[j * N + k], one goal known at a time) and as a
scenario with the goal sequence in extra columns, which LLLG's lifelong runner consumes before
drawing goals of its own (`--lllg BIN` runs it with its README's settings, 1 s per step). Both
then have the same starts, the same goals and the same free-flow bound; LLLG's count (goal
changes over its 500 planning iterations, so arrivals at step 500 are not counted) is reported
as is and with those arrivals added (our count).

    /usr/bin/python3 tools/bench_dense.py --shared --seeds 1 2 3 --lllg /tmp/lllg/build/main \
        --settings warehouse-10-20-10-2-2:800 random-32-32-20:200 --json results/FILE.json

The budget curve (issue 24): GD-RHCR (product default) at each step budget (`--step-budget`,
ms), in both action models, on LLLG's settings, against PIBT (no budget) and, in the mapf model,
LLLG's figure; ms per step is the planner's own mean and max wall time.

    /usr/bin/python3 tools/bench_dense.py --budget-curve [--budgets 10 30 100 300 1000]
        [--models mapf rotation] [--settings MAP:AGENTS ...] [--json results/FILE.json]
"""
import argparse
import json
import os
import random
import re
import shlex
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
    ("PIBT + local guidance (every step)", ["--planner", "pibt", "--guidance", "local"]),
    ("GD-RHCR paper + swap", ["--planner", "gd-rhcr", "--preset", "paper", "--swap", "1"]),
    ("GD-RHCR default without the density rule", ["--planner", "gd-rhcr", "--max-density", "1"]),
    ("GD-RHCR default, guided PIBT for every group", ["--planner", "gd-rhcr", "--solver", "pibt"]),
    ("PIBT + local guidance + motion forecast (8 steps)", ["--planner", "pibt", "--guidance", "local", "--lg-forecast", "8"]),
    ("GD-RHCR default, no motion forecast", ["--planner", "gd-rhcr", "--lg-forecast", "0"]),
    ("GD-RHCR default, motion forecast (8 steps) on every map", ["--planner", "gd-rhcr", "--lg-forecast", "8"]),
    ("GD-RHCR default, collision cost once per step, no far cost (before session 7)",
     ["--planner", "gd-rhcr", "--lg-cost-per-kind", "0", "--lg-far-cost", "-1"]),
    ("GD-RHCR default, no far cost (conflicts cost 3 however far ahead)", ["--planner", "gd-rhcr", "--lg-far-cost", "-1"]),
    ("GD-RHCR default without the contraflow cost (before session 8)", ["--planner", "gd-rhcr", "--lg-contraflow", "0"]),
    ("PIBT + local guidance + contraflow cost", ["--planner", "pibt", "--guidance", "local", "--lg-contraflow", "0.1"]),
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
        "wall_ms_max": 1000 * d["step_wall_time_max_s"], "action_model": d.get("action_model", "mapf"),
        "agents_late": d["progress"]["agents_late"], "late_at_end": d["progress"]["late_at_end"],
        "longest_wait": d["progress"]["longest_wait_steps"], "params": d.get("params", {}),
    }


def budget_curve(args):
    """GD-RHCR at each budget and PIBT, per setting and action model (module text)."""
    rows = []
    print(f"# GD-RHCR against the step budget: random goals, {args.steps} steps, seed {args.seed}\n")
    print("| map | agents | model | planner | budget ms | throughput | vs PIBT | vs LLLG | ms/step mean | ms/step max |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for setting in args.settings:
        m, a = parse_setting(setting)
        for model in args.models:
            runs = [("PIBT", None, ["--planner", "pibt"])]
            runs += [("GD-RHCR", b, ["--planner", "gd-rhcr", "--step-budget", f"{b / 1000:g}"]) for b in args.budgets]
            lllg = LLLG.get((m, a)) if model == "mapf" else None
            pibt = None  # the first run's throughput, the reference of the rest
            for label, budget, pargs in runs:
                r = run(args.sim, m, a, pargs + ["--action-model", model], args.steps, args.seed)
                r.update(planner=label, budget_ms=budget, action_model=model)
                if pibt is None:
                    pibt = r["throughput"]
                r["lllg_throughput"] = lllg[0] if lllg else None
                rows.append(r)
                vs_lllg = f"{100 * r['throughput'] / lllg[0]:.0f}%" if lllg else "-"
                print(f"| {m} | {a} | {model} | {label} | {f'{budget:g}' if budget is not None else '-'} | "
                      f"{r['throughput']:.2f} | {100 * r['throughput'] / pibt:.0f}% | {vs_lllg} | "
                      f"{r['wall_ms']:.2f} | {r['wall_ms_max']:.1f} |", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"rows": rows, "steps": args.steps, "seed": args.seed, "budgets_ms": args.budgets}, f, indent=1)
        print(f"\nwrote {args.json}")
    return rows


def parse_setting(text):
    m, sep, a = text.rpartition(":")
    if not sep or not m or not a.isdigit() or int(a) <= 0:
        raise SystemExit(f"bench_dense: setting '{text}' is not MAP:AGENTS (e.g. random-32-32-20:300)")
    if not os.path.exists(os.path.join(TOP, "maps", m + ".map")):
        raise SystemExit(f"bench_dense: setting '{text}': no map maps/{m}.map")
    return m, int(a)


def write_shared_instance(map_name, agents, seed, out, goals_per_agent=40):
    """The shared instance (see the module text); returns the LoRR problem and scenario paths."""
    map_path = os.path.join(TOP, "maps", map_name + ".map")
    with open(map_path) as f:
        lines = f.read().split("\n")
    h, w = int(lines[1].split()[1]), int(lines[2].split()[1])
    free = [(x, y) for y in range(h) for x in range(w) if lines[4 + y][x] not in "@T"]
    rng = random.Random(seed * 7919 + 17)
    starts = rng.sample(free, agents)
    goals = []
    for s in starts:
        seq, prev = [], s
        for _ in range(goals_per_agent):
            g = prev
            while g == prev:
                g = rng.choice(free)
            seq.append(g)
            prev = g
        goals.append(seq)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    cell = lambda c: c[1] * w + c[0]
    with open(out + ".agents", "w") as f:
        f.write(f"{agents}\n" + "".join(f"{cell(c)}\n" for c in starts))
    with open(out + ".tasks", "w") as f:
        f.write(f"{agents * goals_per_agent}\n" +
                "".join(f"{cell(goals[k][j])}\n" for j in range(goals_per_agent) for k in range(agents)))
    with open(out + ".json", "w") as f:
        json.dump({"mapFile": map_path, "agentFile": os.path.abspath(out + ".agents"),
                   "taskFile": os.path.abspath(out + ".tasks"), "teamSize": agents, "numTasksReveal": 1,
                   "taskAssignmentStrategy": "roundrobin"}, f)
    with open(out + ".scen", "w") as f:
        f.write("version 1\n")
        for k in range(agents):
            cols = [0, map_name + ".map", w, h, starts[k][0], starts[k][1]] + [v for g in goals[k] for v in g]
            f.write("\t".join(map(str, cols)) + "\n")
    return out + ".json", out + ".scen"


def run_shared_sim(sim, problem, args, steps):
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        out = f.name
    subprocess.run([sim, "--lorr-problem", problem, "--steps", str(steps), "--quiet", "--out", out] + args,
                   check=True, stdout=subprocess.DEVNULL)
    with open(out) as f:
        d = json.load(f)
    os.unlink(out)
    return {"throughput": d["throughput"], "free_flow": d["free_flow_throughput"],
            "cpu_ms": 1000 * d["step_cpu_time_mean_s"], "wall_ms": 1000 * d["step_wall_time_mean_s"],
            "longest_wait": d["progress"]["longest_wait_steps"], "params": d.get("params", {})}


def run_shared_lllg(binary, map_name, agents, seed, scen, steps, out):
    """LLLG on the shared scenario with its README's settings; its count and ours."""
    cmd = [binary, "-i", scen, "-m", os.path.join(TOP, "maps", map_name + ".map"), "-N", str(agents), "-s", str(seed),
           "-v", "1", "--lg", "--lg_window", "20", "--lacam_horizon", "10", "--lifelong", "-S", str(steps),
           "-t", "1", "-o", out]
    log = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout
    tasks = int(re.search(r"total_completed_tasks=(\d+)", log).group(1))
    comp_ms = float(re.search(r"comp_time_ms=([0-9.e+]+)", log).group(1))
    # Arrivals at the last step: the executed configuration `steps` on the goals then in force.
    pt = re.compile(r"\((\d+),(\d+)\)")
    goals_last = sol_last = None
    section = None
    with open(out) as f:
        for line in f:
            if line.startswith("goals="):
                section = "goals"
            elif line.startswith("solution="):
                section = "solution"
            elif line.startswith(f"{steps}:"):
                cells = pt.findall(line)
                if section == "goals":
                    goals_last = cells
                elif section == "solution":
                    sol_last = cells
    last = sum(1 for g, c in zip(goals_last, sol_last) if g == c) if goals_last and sol_last else 0
    return {"tasks": tasks, "throughput": tasks / steps, "throughput_our_count": (tasks + last) / steps,
            "ms_per_step": comp_ms / steps, "command": " ".join(cmd)}


def shared(args):
    print(f"# Like for like: the same starts and goal sequences for both, {args.steps} steps\n")
    print("| map | agents | seed | free flow | GD-RHCR | of free flow | cpu ms | LLLG (its count; ours) | of free flow | GD-RHCR vs LLLG |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for setting in args.settings:
        m, a = parse_setting(setting)
        for seed in args.seeds:
            base = os.path.join(args.instance_dir, f"{m}_{a}_s{seed}")
            problem, scen = write_shared_instance(m, a, seed, base)
            r = run_shared_sim(args.sim, problem, args.planner_args, args.steps)
            r.update({"map": m, "agents": a, "seed": seed, "planner_args": args.planner_args})
            line = (f"| {m} | {a} | {seed} | {r['free_flow']:.2f} | {r['throughput']:.2f} | "
                    f"{100 * r['throughput'] / r['free_flow']:.1f}% | {r['cpu_ms']:.1f} |")
            if args.lllg:
                lr = run_shared_lllg(args.lllg, m, a, seed, scen, args.steps, base + ".lllg.txt")
                r["lllg"] = lr
                line += (f" {lr['throughput']:.2f}; {lr['throughput_our_count']:.2f} | "
                         f"{100 * lr['throughput_our_count'] / r['free_flow']:.1f}% | "
                         f"{100 * r['throughput'] / lr['throughput_our_count']:.1f}% |")
            else:
                line += " | | |"
            print(line, flush=True)
            rows.append(r)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"shared_instances": rows}, f, indent=1)
        print(f"\nwrote {args.json}")


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
    ap.add_argument("--shared", action="store_true", help="like for like: shared instances (module text)")
    ap.add_argument("--settings", nargs="+", default=[f"{m}:{a}" for m, a in LLLG], help="MAP:AGENTS for --shared")
    ap.add_argument("--seeds", nargs="+", type=int, default=[1], help="seeds for --shared")
    ap.add_argument("--lllg", help="LLLG binary for --shared (not run without it)")
    ap.add_argument("--instance-dir", default=os.path.join(tempfile.gettempdir(), "gdrhcr_shared"))
    ap.add_argument("--planner-args", default="--planner gd-rhcr",
                    help="gdrhcr_sim options for --shared, one string (--planner-args='--planner gd-rhcr --V 3')")
    ap.add_argument("--budget-curve", action="store_true", help="GD-RHCR at each --budgets, both --models (module text)")
    ap.add_argument("--budgets", nargs="+", type=float, default=[10, 30, 100, 300, 1000], help="ms per step")
    ap.add_argument("--models", nargs="+", choices=["mapf", "rotation"], default=["mapf", "rotation"])
    args = ap.parse_args(argv)
    if args.budget_curve:
        if any(b <= 0 for b in args.budgets):
            raise SystemExit("bench_dense: --budgets must be positive (ms per step)")
        if not os.access(args.sim, os.X_OK):
            raise SystemExit(f"bench_dense: simulator {args.sim} not found or not executable (build it: bash scripts/build_core.sh)")
        budget_curve(args)
        return
    if args.shared:
        args.planner_args = shlex.split(args.planner_args)
        shared(args)
        return
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
