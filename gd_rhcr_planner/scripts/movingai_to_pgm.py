#!/usr/bin/env python3
"""Converts a MovingAI .map into a map_server map (PGM P5 + YAML), optionally cropped.

    movingai_to_pgm.py IN.map OUT_BASENAME [--resolution 1.0] [--crop X0 Y0 W H] [--wall]

Free cells ('.', 'G', 'S', ...) become 254 (white), obstacles ('@', 'T', 'O', 'W') 0 (black).
With --wall the crop's outer ring is made obstacle, closing cut-open corridors.
"""
import argparse
import os

BLOCKED = set("@TOW")


def read_movingai(path):
    with open(path) as f:
        lines = f.read().splitlines()
    i = lines.index("map")
    return [row for row in lines[i + 1:] if row]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("src")
    ap.add_argument("out")
    ap.add_argument("--resolution", type=float, default=1.0)
    ap.add_argument("--crop", type=int, nargs=4, metavar=("X0", "Y0", "W", "H"))
    ap.add_argument("--wall", action="store_true")
    a = ap.parse_args()
    rows = read_movingai(a.src)
    if a.crop:
        x0, y0, w, h = a.crop
        rows = [r[x0:x0 + w] for r in rows[y0:y0 + h]]
    h, w = len(rows), len(rows[0])
    pix = bytearray()
    for y, r in enumerate(rows):
        for x, ch in enumerate(r):
            edge = a.wall and (x in (0, w - 1) or y in (0, h - 1))
            pix.append(0 if (ch in BLOCKED or edge) else 254)
    with open(a.out + ".pgm", "wb") as f:
        f.write(b"P5\n# converted from %s\n%d %d\n255\n" % (os.path.basename(a.src).encode(), w, h))
        f.write(bytes(pix))
    with open(a.out + ".yaml", "w") as f:
        f.write("# map_server map converted from %s by gd_rhcr_planner/scripts/movingai_to_pgm.py%s\n"
                % (os.path.basename(a.src), " (crop %s)" % " ".join(map(str, a.crop)) if a.crop else ""))
        f.write("image: %s.pgm\nresolution: %s\norigin: [0.0, 0.0, 0.0]\n" % (os.path.basename(a.out), a.resolution))
        f.write("negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n")


if __name__ == "__main__":
    main()
