"""Grid cells <-> the `map` frame, the same convention as gd_rhcr_planner/map_loader.hpp.

Cells are (x, y) with x the column and y the row counted from the TOP of the map file.
nav_msgs/OccupancyGrid row r (from the origin, bottom) holds grid row height-1-r.
"""
import math


class GridFrame(object):
    def __init__(self, width, height, resolution, origin_x, origin_y, data):
        self.width = width
        self.height = height
        self.resolution = resolution
        self.origin_x = origin_x
        self.origin_y = origin_y
        self.data = data  # OccupancyGrid data, row 0 at the bottom

    @classmethod
    def from_occupancy_grid(cls, msg):
        i = msg.info
        return cls(i.width, i.height, i.resolution, i.origin.position.x, i.origin.position.y, list(msg.data))

    def in_bounds(self, x, y):
        return 0 <= x < self.width and 0 <= y < self.height

    def is_free(self, x, y):
        return self.in_bounds(x, y) and self.data[(self.height - 1 - y) * self.width + x] == 0

    def free_cells(self):
        return [(x, y) for y in range(self.height) for x in range(self.width) if self.is_free(x, y)]

    def world(self, x, y):
        return (self.origin_x + (x + 0.5) * self.resolution,
                self.origin_y + (self.height - 1 - y + 0.5) * self.resolution)

    def cell(self, wx, wy):
        x = int(math.floor((wx - self.origin_x) / self.resolution))
        return x, self.height - 1 - int(math.floor((wy - self.origin_y) / self.resolution))


def tick_entry_taken(update_tick, tick):
    """Whether a robot takes its entry of a tick-`tick` step_commands array after its last
    step_command_updates entry followed tick `update_tick` (-1: none). The two topics are not
    ordered: an array of that tick (or the one before) arriving after the update is older than the
    update and is not taken. A tick number further back means the manager restarted (its ticks
    count from 1 again): taken."""
    return not (0 <= update_tick - tick <= 1)


def adjacent_or_same(a, b):
    return abs(a[0] - b[0]) + abs(a[1] - b[1]) <= 1


def resolve_moves(cells, targets, frozen, reserved=()):
    """Which commanded moves may start now without two robots ever sharing a cell.

    cells[i]: robot i's cell; targets[i]: its commanded cell (adjacent or equal); frozen[i]:
    True for a robot that will not move (stalled, offline, still moving); reserved: cells that
    robots still moving are entering (their cell in `cells` is the one they leave). A move starts
    unless its target is held by a robot that stays (directly or behind a chain of blocked
    robots), is reserved, or is a swap. Returns (moves: set of robot ids that start, blocked:
    ids whose move waits).
    """
    reserved = set(reserved)
    n = len(cells)
    movers = set(i for i in range(n) if not frozen[i] and targets[i] != cells[i])
    at = {c: i for i, c in enumerate(cells)}
    blocked = set()
    changed = True
    while changed:
        changed = False
        for i in sorted(movers):
            j = at.get(targets[i])
            stays = j is not None and (j not in movers)
            swap = j is not None and j in movers and targets[j] == cells[i]
            if stays or swap or targets[i] in reserved:
                movers.discard(i)
                blocked.add(i)
                changed = True
    # Two movers into one cell (never commanded by a valid plan): let the lower id go.
    seen = {}
    for i in sorted(movers):
        if targets[i] in seen:
            blocked.add(i)
        else:
            seen[targets[i]] = i
    movers -= blocked
    return movers, blocked
