#!/usr/bin/env python3
"""Draws one step's GD-RHCR groups on a map (the paper's figure 2): agents within
shortest-path distance V are linked by lines, and each group (connected component) has a colour
(colours are reused).

    build/src/gdrhcr_sim --map maps/empty-48-48.map --agents 150 --steps 20 --paths /tmp/p.txt
    tools/plot_groups.py --map maps/empty-48-48.map --paths /tmp/p.txt --step 10 --V 2 --out groups.png
"""
import argparse
import sys
from collections import deque

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from grid_files import BLOCKED, read_map, read_paths  # noqa: E402


def read_positions(path, step, width, height):
    paths = read_paths(path, width, height)
    if step >= len(paths[0]):
        raise SystemExit("plot_groups: the paths file has only %d steps" % (len(paths[0]) - 1))
    return [p[step] for p in paths]


def groups(rows, pos, V):
    """Union-find over agents linked by a depth-V BFS through free cells."""
    free = lambda x, y: 0 <= y < len(rows) and 0 <= x < len(rows[0]) and rows[y][x] not in BLOCKED
    at = {p: i for i, p in enumerate(pos)}
    parent = list(range(len(pos)))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    links = []
    for i, s in enumerate(pos):
        seen = {s}
        q = deque([(s, 0)])
        while q:
            (x, y), d = q.popleft()
            j = at.get((x, y))
            if j is not None and j > i:
                links.append((i, j))
                parent[find(i)] = find(j)
            if d == V:
                continue
            for n in ((x + 1, y), (x - 1, y), (x, y + 1), (x, y - 1)):
                if n not in seen and free(*n):
                    seen.add(n)
                    q.append((n, d + 1))
    return [find(i) for i in range(len(pos))], links


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--map", required=True)
    ap.add_argument("--paths", required=True, help="gdrhcr_sim --paths output")
    ap.add_argument("--step", type=int, default=0)
    ap.add_argument("--V", type=int, default=2)
    ap.add_argument("--out", required=True)
    args = ap.parse_args(argv)
    rows = read_map(args.map)
    pos = read_positions(args.paths, args.step, len(rows[0]), len(rows))
    comp, links = groups(rows, pos, args.V)
    h, w = len(rows), len(rows[0])
    fig, ax = plt.subplots(figsize=(max(4, w / 8), max(4, h / 8)))
    img = [[0.15 if c in BLOCKED else 1.0 for c in r] for r in rows]
    ax.imshow(img, cmap="gray", vmin=0, vmax=1, interpolation="nearest")
    palette = plt.get_cmap("tab10")
    ids = {r: k for k, r in enumerate(sorted(set(comp)))}
    for i, j in links:
        ax.plot([pos[i][0], pos[j][0]], [pos[i][1], pos[j][1]], color=palette(ids[comp[i]] % 10), lw=1.5)
    ax.scatter([p[0] for p in pos], [p[1] for p in pos], s=18,
               c=[palette(ids[c] % 10) for c in comp], edgecolors="black", linewidths=0.4, zorder=3)
    sizes = sorted((comp.count(r) for r in set(comp)), reverse=True)
    ax.set_title("%d agents, V = %d, step %d: %d groups (largest %d)"
                 % (len(pos), args.V, args.step, len(sizes), sizes[0] if sizes else 0), fontsize=9)
    ax.set_xticks([])
    ax.set_yticks([])
    fig.tight_layout()
    fig.savefig(args.out, dpi=130)
    print("wrote %s: %d groups, sizes %s" % (args.out, len(sizes), sizes[:10]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
