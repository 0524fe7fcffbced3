"""The map and path files the tools read: MovingAI maps (and RHCR's kiva maps) and the paths
`gdrhcr_sim --paths` writes. Errors are ValueErrors naming the file and what is wrong."""
import re

BLOCKED = set("@TOW")  # MovingAI's obstacles; every other letter is passable, as in grid.cpp
CELL = re.compile(r"\((\d+),(\d+)\)")


def read_map(path):
    """The map's rows of cells: MovingAI ('type', 'height H', 'width W', 'map', then H rows of W
    cells) or RHCR's kiva format (4 header lines, then rows of one width)."""
    with open(path) as f:
        lines = [line.rstrip("\r\n") for line in f]
    if lines and lines[0].startswith("type"):
        try:
            height = int(lines[1].split()[1])
            width = int(lines[2].split()[1])
            if lines[3].strip() != "map":
                raise ValueError("fourth line is not 'map'")
        except (IndexError, ValueError) as e:
            raise ValueError(f"{path}: not a MovingAI map header ({e})") from None
        rows = [r[:width] for r in lines[4:4 + height]]
        if len(rows) < height or any(len(r) < width for r in rows):
            raise ValueError(f"{path}: fewer than {height} rows of {width} cells")
        return rows
    rows = [r for r in lines[4:] if r]
    if not rows or any(len(r) != len(rows[0]) for r in rows):
        raise ValueError(f"{path}: not a MovingAI map header, nor a kiva map (4 header lines, then rows of one width)")
    return rows


def read_paths(path, width, height):
    """One list of (x, y) per agent, in agent order, all of the same length."""
    paths = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            if not line.strip():
                continue
            head, sep, rest = line.partition(":")
            if not sep or not head.strip().isdigit() or int(head) != len(paths):
                raise ValueError(f"{path}:{n}: expected 'agent: (x,y),...' for agent {len(paths)}")
            cells = [(int(x), int(y)) for x, y in CELL.findall(rest)]
            if not cells or any(x >= width or y >= height for x, y in cells):
                raise ValueError(f"{path}:{n}: no cells, or a cell outside the {width} x {height} map")
            paths.append(cells)
    if not paths or len({len(p) for p in paths}) != 1:
        raise ValueError(f"{path}: no agents, or paths of different lengths")
    return paths
