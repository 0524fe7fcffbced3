#!/usr/bin/env python3
"""Plots a gdrhcr_sweep CSV: per map, throughput, mean plan time and wall time against agents
(mean with a 1-SD band over seeds, one line per label), and GD-RHCR group statistics.

    tools/plot_sweep.py results/paper.csv --out docs/figures [--title-prefix TEXT]
    tools/plot_sweep.py results/paper_mapd.csv --out docs/figures/paper --paper paper_mapd [--markdown]

Writes <out>/<map>_throughput.png, _plan_time.png, _wall_time.png, _groups.png (when the
CSV has group statistics) and _ablation.png (when labels read 'param=value', as in the
ablation configs: one column of panels per parameter), and prints the table of means.

--paper NAME lays the maps out as the paper's figures instead: one column per map (the paper's
order), a throughput row over a plan-time row (log scale), mean and 1-SD bands, one colour per
planner, into <out>/NAME.png; the same layout of wall times per run into <out>/NAME_wall.png
and of GD-RHCR group statistics into <out>/NAME_groups.png. --markdown prints the table of
means (and SDs) per map, agent count and label as Markdown.
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

COLORS = {"GD-RHCR": "tab:red", "GD-RHCR (paper)": "tab:red", "GD-RHCR (default)": "tab:orange",
          "RHCR": "tab:green", "PIBT": "tab:blue", "PIBT (paper)": "tab:purple"}
# The paper's column order in its two figure families; other maps follow alphabetically.
PAPER_ORDER = ["warehouse-10-20-10-2-1", "warehouse-10-20-10-2-2", "sortation-1", "sortation-2",
               "random-64-64-20", "room-64-64-var1", "room-64-64-var2", "random-32-32-20",
               "room-32-32-var1", "empty-48-48"]
LABEL_ORDER = ["GD-RHCR (paper)", "GD-RHCR", "GD-RHCR (default)", "RHCR", "PIBT", "PIBT (paper)"]


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


def label_key(label):
    return (LABEL_ORDER.index(label) if label in LABEL_ORDER else len(LABEL_ORDER), label)


def panel(ax, data, ylabel, log=False, legend=True):
    for i, (label, pts) in enumerate(sorted(data.items(), key=lambda kv: label_key(kv[0]))):
        xs = [p[0] for p in pts]
        mean = [p[1] for p in pts]
        lo = [p[1] - p[2] for p in pts]
        hi = [p[1] + p[2] for p in pts]
        color = COLORS.get(label, "C%d" % (i + 3))
        ax.plot(xs, mean, marker="o", ms=3, color=color, label=label)
        # On a log axis mean - SD can be <= 0: the band's lower edge is clipped at a tenth of the mean.
        lo = [max(v, 0.1 * m) for v, m in zip(lo, mean)] if log else lo
        ax.fill_between(xs, lo, hi, color=color, alpha=0.2)
    ax.set_xlabel("agents")
    ax.set_ylabel(ylabel)
    if log:
        ax.set_yscale("log")
    ax.grid(alpha=0.3)
    if legend:
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


def keep_min_seeds(rows, n):
    seeds = defaultdict(set)
    for r in rows:
        seeds[(r["label"], r["map"], r["agents"])].add(r["seed"])
    return [r for r in rows if len(seeds[(r["label"], r["map"], r["agents"])]) >= n]


def map_name(row):
    return os.path.splitext(os.path.basename(row["map"]))[0]


def map_order(names):
    return sorted(names, key=lambda n: (PAPER_ORDER.index(n) if n in PAPER_ORDER else len(PAPER_ORDER), n))


def plot_paper(rows, name, out, prefix):
    """The paper's layout: a column per map; rows of metrics; one shared legend."""
    by_map = defaultdict(list)
    for r in rows:
        by_map[map_name(r)].append(r)
    maps = map_order(by_map)
    layouts = [("", [("throughput", "throughput [goals / step]", False),
                     ("plan_time_mean_s", "mean plan time [s]", True)]),
               ("_wall", [("wall_time_s", "wall time per run [s]", True)]),
               ("_groups", [("groups_mean_count", "mean number of groups", False),
                            ("groups_mean_size", "mean group size", False),
                            ("groups_mean_max_size", "mean max group size", False)])]
    files = []
    for suffix, metrics in layouts:
        if not any(series(by_map[m], metric) for m in maps for metric, _, _ in metrics):
            continue
        fig, axes = plt.subplots(len(metrics), len(maps), figsize=(2.9 * len(maps), 2.5 * len(metrics) + 0.9),
                                 squeeze=False)
        handles = {}
        for c, m in enumerate(maps):
            for r, (metric, ylabel, log) in enumerate(metrics):
                ax = axes[r][c]
                panel(ax, series(by_map[m], metric), ylabel if c == 0 else "", log, legend=False)
                if r == 0:
                    ax.set_title("%s\n(%s)" % (m, seeds_steps(by_map[m])), fontsize=9)
                if r < len(metrics) - 1:
                    ax.set_xlabel("")
                ax.tick_params(labelsize=7)
                for h, l in zip(*ax.get_legend_handles_labels()):
                    handles.setdefault(l, h)
        labels = sorted(handles, key=label_key)
        fig.legend([handles[l] for l in labels], labels, loc="lower center", ncol=len(labels), fontsize=9,
                   frameon=False)
        fig.suptitle("%s%s (mean and 1 SD over seeds)" % (prefix, name), fontsize=10)
        fig.tight_layout(rect=(0, 0.06, 1, 0.96))
        path = os.path.join(out, "%s%s.png" % (name, suffix))
        fig.savefig(path, dpi=110)
        plt.close(fig)
        files.append(path)
    return files


def markdown_table(rows):
    """Mean ± SD throughput and mean plan time per map, agent count and label (n=seeds when a
    label has fewer seeds at that point than the most any label has)."""
    by_map = defaultdict(list)
    for r in rows:
        by_map[map_name(r)].append(r)
    labels = sorted({r["label"] for r in rows}, key=label_key)
    lines = ["| map | agents | seeds | " + " | ".join("%s tp" % l for l in labels) + " | "
             + " | ".join("%s plan s" % l for l in labels) + " |",
             "|" + "---|" * (3 + 2 * len(labels))]
    for m in map_order(by_map):
        tp, pt = series(by_map[m], "throughput"), series(by_map[m], "plan_time_mean_s")
        agents = sorted({int(r["agents"]) for r in by_map[m]})
        for a in agents:
            seeds = len({r["seed"] for r in by_map[m] if int(r["agents"]) == a})
            cells = []
            for l in labels:
                p = [x for x in tp.get(l, []) if x[0] == a]
                cells.append(("%.3f ± %.3f" % (p[0][1], p[0][2]) + (" (n=%d)" % p[0][3] if p[0][3] != seeds else ""))
                             if p else "-")
            for l in labels:
                p = [x for x in pt.get(l, []) if x[0] == a]
                cells.append("%.4f" % p[0][1] if p else "-")
            lines.append("| %s | %d | %d | %s |" % (m, a, seeds, " | ".join(cells)))
    return "\n".join(lines)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--out", required=True)
    ap.add_argument("--title-prefix", default="")
    ap.add_argument("--paper", metavar="NAME", help="the paper's layout, into <out>/NAME.png (see above)")
    ap.add_argument("--markdown", action="store_true", help="print the table of means as Markdown")
    ap.add_argument("--min-seeds", type=int, default=1,
                    help="leave out points (label, map, agents) with fewer finished seeds than this")
    args = ap.parse_args(argv)
    rows = load(args.csv)
    if args.min_seeds > 1:
        rows = keep_min_seeds(rows, args.min_seeds)
        if not rows:
            raise SystemExit("plot_sweep: no point of %s has %d seeds" % (args.csv, args.min_seeds))
    os.makedirs(args.out, exist_ok=True)
    if args.paper:
        for path in plot_paper(rows, args.paper, args.out, args.title_prefix):
            print("wrote", path)
        if args.markdown:
            print(markdown_table(rows))
        return 0
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
