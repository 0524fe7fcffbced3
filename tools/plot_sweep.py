#!/usr/bin/env python3
"""Plots a gdrhcr_sweep CSV: per map, throughput, mean plan time and wall time against agents
(mean with a 1-SD band over seeds, one line per label), and GD-RHCR group statistics.

    tools/plot_sweep.py results/paper.csv --out docs/figures [--title-prefix TEXT]

Writes <out>/<map>_throughput.png, _plan_time.png, _wall_time.png, _groups.png (when the
CSV has group statistics) and _ablation.png (when labels read 'param=value', as in the
ablation configs: one column of panels per parameter), and prints the table of means.
"""
import argparse
import csv
import math
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

COLORS = {"GD-RHCR": "tab:red", "RHCR": "tab:green", "PIBT": "tab:blue"}


def load(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r.get("status") == "ok"]
    if not rows:
        raise SystemExit("plot_sweep: %s has no finished runs" % path)
    return rows


def stats(values):
    n = len(values)
    mean = sum(values) / n
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 else 0.0
    return mean, sd, n


def series(rows, metric):
    """{label: [(agents, mean, sd, n), ...]} for one map, skipping empty cells."""
    by = defaultdict(lambda: defaultdict(list))
    for r in rows:
        if r.get(metric, "") not in ("", None):
            by[r["label"]][int(r["agents"])].append(float(r[metric]))
    return {label: [(a,) + stats(v) for a, v in sorted(d.items())] for label, d in by.items()}


def panel(ax, data, ylabel, log=False):
    for i, (label, pts) in enumerate(sorted(data.items())):
        xs = [p[0] for p in pts]
        mean = [p[1] for p in pts]
        lo = [p[1] - p[2] for p in pts]
        hi = [p[1] + p[2] for p in pts]
        color = COLORS.get(label, "C%d" % (i + 3))
        ax.plot(xs, mean, marker="o", ms=3, color=color, label=label)
        ax.fill_between(xs, [max(v, 1e-9) if log else v for v in lo], hi, color=color, alpha=0.2)
    ax.set_xlabel("agents")
    ax.set_ylabel(ylabel)
    if log:
        ax.set_yscale("log")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def seeds_steps(rows):
    seeds = sorted({r["seed"] for r in rows})
    steps = sorted({r["steps"] for r in rows})
    return "%d seeds, %s steps" % (len(seeds), "/".join(steps))


def plot_map(rows, name, out, prefix):
    files = []
    figs = [("throughput", "throughput [goals / step]", False),
            ("plan_time_mean_s", "mean plan time [s]", True),
            ("wall_time_s", "wall time per run [s]", True)]
    for metric, ylabel, log in figs:
        data = series(rows, metric)
        if not data:
            continue
        fig, ax = plt.subplots(figsize=(5, 3.6))
        panel(ax, data, ylabel, log)
        ax.set_title("%s%s: %s\n(%s, mean and 1 SD)" % (prefix, name, metric.replace("_", " "), seeds_steps(rows)), fontsize=9)
        fig.tight_layout()
        path = os.path.join(out, "%s_%s.png" % (name, metric.replace("_mean_s", "").replace("_s", "")))
        fig.savefig(path, dpi=120)
        plt.close(fig)
        files.append(path)
    group_metrics = [("groups_mean_count", "mean number of groups"),
                     ("groups_mean_size", "mean group size"),
                     ("groups_mean_max_size", "mean max group size")]
    gdata = [(m, y, series(rows, m)) for m, y in group_metrics]
    if any(d for _, _, d in gdata):
        fig, axes = plt.subplots(1, 3, figsize=(12, 3.4))
        for ax, (m, y, d) in zip(axes, gdata):
            panel(ax, d, y)
        fig.suptitle("%s%s: GD-RHCR group statistics (%s)" % (prefix, name, seeds_steps(rows)), fontsize=10)
        fig.tight_layout()
        path = os.path.join(out, "%s_groups.png" % name)
        fig.savefig(path, dpi=120)
        plt.close(fig)
        files.append(path)
    return files


def plot_ablation(rows, name, out, prefix):
    """Labels of the form 'param=value' (ablation configs): one column per parameter, rows for
    throughput and mean plan time, one line per value."""
    params = sorted({r["label"].split("=", 1)[0] for r in rows if "=" in r["label"]})
    if not params:
        return []
    fig, axes = plt.subplots(2, len(params), figsize=(4.2 * len(params), 6.4), squeeze=False)
    for c, param in enumerate(params):
        prows = [r for r in rows if r["label"].split("=", 1)[0] == param]
        panel(axes[0][c], series(prows, "throughput"), "throughput [goals / step]")
        panel(axes[1][c], series(prows, "plan_time_mean_s"), "mean plan time [s]", log=True)
        axes[0][c].set_title("varying %s" % param, fontsize=9)
    fig.suptitle("%s%s ablations (%s, mean and 1 SD)" % (prefix, name, seeds_steps(rows)), fontsize=10)
    fig.tight_layout()
    path = os.path.join(out, "%s_ablation.png" % name)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return [path]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--out", required=True)
    ap.add_argument("--title-prefix", default="")
    args = ap.parse_args(argv)
    rows = load(args.csv)
    os.makedirs(args.out, exist_ok=True)
    by_map = defaultdict(list)
    for r in rows:
        by_map[os.path.splitext(os.path.basename(r["map"]))[0]].append(r)
    for name, mrows in sorted(by_map.items()):
        for path in plot_map(mrows, name, args.out, args.title_prefix) + plot_ablation(mrows, name, args.out, args.title_prefix):
            print("wrote", path)
        print("%s (%s)" % (name, seeds_steps(mrows)))
        print("  %-12s %7s %11s %9s %14s" % ("label", "agents", "throughput", "sd", "plan_time_s"))
        tp = series(mrows, "throughput")
        pt = series(mrows, "plan_time_mean_s")
        for label in sorted(tp):
            ptd = {p[0]: p[1] for p in pt.get(label, [])}
            for a, mean, sd, n in tp[label]:
                print("  %-12s %7d %11.3f %9.3f %14.6f" % (label, a, mean, sd, ptd.get(a, float("nan"))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
