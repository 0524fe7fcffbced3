#!/usr/bin/env python3
"""Where a run's agents jam, from its executed paths (issue 24: where the errands are lost).
Prints figures; it is not a test.

Reads a map (MovingAI .map) and the paths `gdrhcr_sim --paths FILE` writes (one line per agent,
'i: (x,y),(x,y),...', one cell per timestep) and prints:
  - the share of agents that moved, per window of steps: a jam that grows shows as a share that
    keeps falling;
  - at each step given with --at: how many agents have stood still 5, 20 and 50 steps or more
    (a deadlock shows as agents standing for ever, stop-and-go traffic does not), the largest
    clusters of touching agents (8-neighbourhood) with their bounding boxes, and a map of blocks
    whose digit is the tenths of the block's free cells that hold an agent ('.' none, blank no
    free cell).

    /usr/bin/python3 tools/jam_report.py --map MAP --paths PATHS [--at T ...] [--window 100]
        [--block 8] [--clusters 5] [--json FILE]

Example (docs/results.md, session 23):
    build/src/gdrhcr_sim --lorr-problem .../MR23-I-02.json --planner gd-rhcr --steps 3500 \\
        --seed 0 --traffic-cost 2 --quiet --out r.json --paths p.txt
    /usr/bin/python3 tools/jam_report.py --map .../Paris_1_256.map --paths p.txt --at 500 3400
"""
import argparse
import json
import sys

from grid_files import BLOCKED, read_map, read_paths


def moving_share(paths, window):
    """[(first step, last step, share of agent-steps that moved)] per window of steps."""
    steps = len(paths[0]) - 1
    out = []
    for t0 in range(0, steps, window):
        t1 = min(steps, t0 + window)
        moved = sum(p[t + 1] != p[t] for p in paths for t in range(t0, t1))
        out.append((t0, t1 - 1, moved / (len(paths) * (t1 - t0))))
    return out


def standing(paths, t):
    """Per agent, the steps it has stood in its cell at step t."""
    out = []
    for p in paths:
        k = 0
        while t - k - 1 >= 0 and p[t - k - 1] == p[t]:
            k += 1
        out.append(k)
    return out


def clusters(paths, t):
    """Clusters of agents touching at step t (8-neighbourhood), largest first: (size, x0, y0, x1, y1)."""
    cells = {p[t] for p in paths}
    seen, out = set(), []
    for start in sorted(cells):
        if start in seen:
            continue
        seen.add(start)
        stack, members = [start], []
        while stack:
            x, y = stack.pop()
            members.append((x, y))
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    q = (x + dx, y + dy)
                    if q in cells and q not in seen:
                        seen.add(q)
                        stack.append(q)
        xs, ys = [c[0] for c in members], [c[1] for c in members]
        out.append((len(members), min(xs), min(ys), max(xs), max(ys)))
    out.sort(key=lambda c: -c[0])
    return out


def density_rows(rows, paths, t, block):
    """One string per row of blocks: the tenths of a block's free cells holding an agent."""
    count = {}
    for p in paths:
        x, y = p[t]
        count[(y // block, x // block)] = count.get((y // block, x // block), 0) + 1
    height, width = len(rows), len(rows[0])
    out = []
    for by in range((height + block - 1) // block):
        line = ""
        for bx in range((width + block - 1) // block):
            free = sum(rows[y][x] not in BLOCKED for y in range(by * block, min(height, by * block + block))
                       for x in range(bx * block, min(width, bx * block + block)))
            c = count.get((by, bx), 0)
            line += " " if free == 0 else "." if c == 0 else str(min(9, 10 * c // free))
        out.append(line)
    return out


def report(rows, paths, at, window, block, top):
    steps = len(paths[0]) - 1
    result = {"agents": len(paths), "steps": steps, "moving_share": moving_share(paths, window), "at": []}
    for t in at:
        if not 0 <= t < steps:
            raise ValueError(f"--at {t}: the paths cover steps 0..{steps - 1}")
        stood = standing(paths, t)
        result["at"].append({
            "step": t,
            "stood_5": sum(s >= 5 for s in stood),
            "stood_20": sum(s >= 20 for s in stood),
            "stood_50": sum(s >= 50 for s in stood),
            "clusters": clusters(paths, t)[:top],
            "density": density_rows(rows, paths, t, block),
        })
    return result


def print_report(result, block):
    print(f"{result['agents']} agents, {result['steps']} steps")
    for t0, t1, share in result["moving_share"]:
        print(f"steps {t0:5d}-{t1:5d}: moved in {100 * share:.0f}% of agent-steps")
    for a in result["at"]:
        print(f"\nstep {a['step']}: stood 5+ steps {a['stood_5']}, 20+ {a['stood_20']}, 50+ {a['stood_50']}")
        for size, x0, y0, x1, y1 in a["clusters"]:
            print(f"  cluster of {size} touching agents in x {x0}-{x1}, y {y0}-{y1}")
        print(f"  agents per free cell in {block} x {block} blocks (tenths):")
        for k, line in enumerate(a["density"]):
            print(f"  {k * block:4d} {line}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--map", required=True)
    ap.add_argument("--paths", required=True)
    ap.add_argument("--at", type=int, nargs="*", default=[])
    ap.add_argument("--window", type=int, default=100)
    ap.add_argument("--block", type=int, default=8)
    ap.add_argument("--clusters", type=int, default=5)
    ap.add_argument("--json")
    args = ap.parse_args(argv)
    if args.window < 1 or args.block < 1 or args.clusters < 0:
        ap.error("--window and --block must be at least 1, --clusters at least 0")
    try:
        rows = read_map(args.map)
        paths = read_paths(args.paths, len(rows[0]), len(rows))
        result = report(rows, paths, args.at, args.window, args.block, args.clusters)
    except (OSError, ValueError) as e:
        print(f"jam_report: {e}", file=sys.stderr)
        return 2
    print_report(result, args.block)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
