#!/usr/bin/env python3
"""Prints GD-RHCR against RHCR and PIBT from a sweep CSV, per map and agent count:
mean throughput of each, GD-RHCR's throughput relative to RHCR and to PIBT, and how many
times lower GD-RHCR's mean plan time is than RHCR's (the paper's perfect-parallelism metric:
per step, the slowest group solved; RHCR: per PBS call).

    tools/compare_planners.py results/compare_warehouse.csv [--markdown]
"""
import argparse
import csv
import os
import sys
from collections import defaultdict


def mean(v):
    return sum(v) / len(v) if v else float("nan")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("csv")
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = ap.parse_args(argv)
    data = defaultdict(lambda: defaultdict(list))
    seeds = defaultdict(set)
    with open(args.csv, newline="") as f:
        for r in csv.DictReader(f):
            if r.get("status") != "ok":
                continue
            key = (os.path.splitext(os.path.basename(r["map"]))[0], int(r["agents"]))
            data[key][(r["label"], "tp")].append(float(r["throughput"]))
            data[key][(r["label"], "pt")].append(float(r["plan_time_mean_s"]))
            data[key][(r["label"], "wall")].append(float(r["wall_time_s"]))
            data[key][(r["label"], "fail")].append(float(r["solver_failures"] or 0))
            seeds[key].add(r["seed"])
    if not data:
        sys.exit("compare_planners: no finished runs in " + args.csv)
    cols = ["map", "agents", "seeds", "GD tp", "RHCR tp", "PIBT tp", "GD/RHCR tp", "GD/PIBT tp",
            "GD plan s", "RHCR plan s", "plan speedup", "GD wall s", "RHCR wall s", "RHCR fails/run"]
    rows = []
    for (m, a) in sorted(data):
        d = data[(m, a)]
        g, r, p = (mean(d[(l, "tp")]) for l in ("GD-RHCR", "RHCR", "PIBT"))
        gp, rp = mean(d[("GD-RHCR", "pt")]), mean(d[("RHCR", "pt")])
        gw, rw = mean(d[("GD-RHCR", "wall")]), mean(d[("RHCR", "wall")])
        pct = lambda x, y: "%+.1f%%" % (100 * (x / y - 1)) if y == y and x == x and y > 0 else "-"
        fmt = lambda x, f="%.3f": f % x if x == x else "-"
        rows.append([m, str(a), str(len(seeds[(m, a)])), fmt(g), fmt(r), fmt(p), pct(g, r), pct(g, p),
                     fmt(gp, "%.4f"), fmt(rp, "%.4f"),
                     ("%.1fx" % (rp / gp)) if gp == gp and rp == rp and gp > 0 else "-",
                     fmt(gw, "%.1f"), fmt(rw, "%.1f"), fmt(mean(d[("RHCR", "fail")]), "%.1f")])
    if args.markdown:
        print("| " + " | ".join(cols) + " |")
        print("|" + "---|" * len(cols))
        for row in rows:
            print("| " + " | ".join(row) + " |")
    else:
        widths = [max(len(c), *(len(r[i]) for r in rows)) for i, c in enumerate(cols)]
        print("  ".join(c.rjust(w) for c, w in zip(cols, widths)))
        for row in rows:
            print("  ".join(x.rjust(w) for x, w in zip(row, widths)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
