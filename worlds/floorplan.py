"""Floor plans: a rectangle cut into rooms, doorways that connect them all, and the walls between.

The plan is a guillotine partition (each cut splits one rectangle in two), so every room edge is
either on the outline or shared with neighbours, and walls are exactly the outline plus the shared
edges. Doorways form a random spanning tree over rooms that share enough wall for a door (plus
sometimes one extra door), so every room is reachable by construction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from worlds.things import Rect

WALL_THICKNESS = 0.1
WALL_HEIGHT = 2.5
MIN_ROOM_SIDE = 2.5
DOOR_WIDTH = (0.9, 1.1)
#: Wall left on each side of a doorway, so the door never sits in a corner.
DOOR_MARGIN = 0.45
EXTRA_DOOR_PROBABILITY = 0.5
_EPS = 1e-6


@dataclass(frozen=True)
class SharedEdge:
    """The stretch of wall two rooms share: on line ``at`` (y if along 'x', x if along 'y'), lo..hi."""

    a: int
    b: int
    along: str
    at: float
    lo: float
    hi: float

    @property
    def length(self) -> float:
        return self.hi - self.lo


@dataclass(frozen=True)
class Door:
    """A doorway on a shared edge: the gap's centre along the edge and its width."""

    edge: SharedEdge
    middle: float
    width: float

    @property
    def center(self) -> tuple[float, float]:
        return (self.middle, self.edge.at) if self.edge.along == "x" else (self.edge.at, self.middle)


def split_floor(rng: np.random.Generator, n_rooms: int) -> tuple[Rect, list[Rect]] | None:
    """The outline (about 13-18 m² a room, 40-90 m² in all) and its rooms; None if a cut failed."""
    area = float(np.clip(n_rooms * rng.uniform(13.0, 18.0), 40.0, 90.0))
    aspect = rng.uniform(1.0, 1.6)
    width = round(math.sqrt(area * aspect), 1)
    height = round(area / width, 1)
    outline = (0.0, 0.0, width, height)
    rects = [outline]
    while len(rects) < n_rooms:
        areas = np.array([(r[2] - r[0]) * (r[3] - r[1]) for r in rects])
        x0, y0, x1, y1 = rects.pop(int(rng.choice(len(rects), p=areas / areas.sum())))
        vertical_cut = (x1 - x0) >= (y1 - y0)
        lo, hi = (x0, x1) if vertical_cut else (y0, y1)
        side = hi - lo
        if side < 2 * MIN_ROOM_SIDE:
            return None
        cut = lo + round(rng.uniform(max(0.35 * side, MIN_ROOM_SIDE), min(0.65 * side, side - MIN_ROOM_SIDE)), 1)
        if vertical_cut:
            rects += [(x0, y0, cut, y1), (cut, y0, x1, y1)]
        else:
            rects += [(x0, y0, x1, cut), (x0, cut, x1, y1)]
    return outline, rects


def shared_edges(rects: list[Rect]) -> list[SharedEdge]:
    """Every stretch of wall of positive length that two rooms share."""
    edges = []
    for i, a in enumerate(rects):
        for j in range(i + 1, len(rects)):
            b = rects[j]
            for line_a, line_b, along, lo, hi in (
                ((a[2], b[0]), (a[0], b[2]), "y", max(a[1], b[1]), min(a[3], b[3])),
                ((a[3], b[1]), (a[1], b[3]), "x", max(a[0], b[0]), min(a[2], b[2])),
            ):
                if hi - lo <= _EPS:
                    continue
                for at, other in (line_a, line_b):
                    if abs(at - other) < _EPS:
                        edges.append(SharedEdge(i, j, along, at, lo, hi))
    return edges


def pick_doors(rng: np.random.Generator, n_rooms: int, edges: list[SharedEdge]) -> list[Door] | None:
    """A random spanning tree of doors over rooms, plus maybe one extra; None if rooms can't connect."""
    capable = [e for e in edges if e.length >= DOOR_WIDTH[1] + 2 * DOOR_MARGIN]
    visited = {int(rng.integers(n_rooms))}
    chosen: list[SharedEdge] = []
    while len(visited) < n_rooms:
        options = [e for e in capable if (e.a in visited) != (e.b in visited)]
        if not options:
            return None
        edge = options[int(rng.integers(len(options)))]
        chosen.append(edge)
        visited |= {edge.a, edge.b}
    rest = [e for e in capable if e not in chosen]
    if rest and rng.random() < EXTRA_DOOR_PROBABILITY:
        chosen.append(rest[int(rng.integers(len(rest)))])
    doors = []
    for edge in chosen:
        width = round(rng.uniform(*DOOR_WIDTH), 2)
        slack = edge.length - 2 * DOOR_MARGIN - width
        middle = round(edge.lo + DOOR_MARGIN + width / 2 + rng.uniform(0.0, slack), 2)
        doors.append(Door(edge, middle, width))
    return doors


Box = tuple[tuple[float, float, float], tuple[float, float, float]]


def wall_boxes(outline: Rect, edges: list[SharedEdge], doors: list[Door]) -> list[Box]:
    """Wall boxes as (centre xyz, size xyz): the outline and every shared edge, cut at doorways.

    Each piece reaches half a wall thickness past the ends of its line so corners close; pieces end
    exactly at door jambs so the doorway keeps its full width.
    """
    x0, y0, x1, y1 = outline
    lines = [("x", y0, x0, x1), ("x", y1, x0, x1), ("y", x0, y0, y1), ("y", x1, y0, y1)]
    lines += [(e.along, e.at, e.lo, e.hi) for e in edges]
    half_t = WALL_THICKNESS / 2
    boxes = []
    for along, at, lo, hi in lines:
        gaps = sorted(
            (d.middle - d.width / 2, d.middle + d.width / 2)
            for d in doors
            if d.edge.along == along and abs(d.edge.at - at) < _EPS and lo - _EPS <= d.middle <= hi + _EPS
        )
        start = lo - half_t
        pieces = []
        for gap_lo, gap_hi in gaps:
            pieces.append((start, gap_lo))
            start = gap_hi
        pieces.append((start, hi + half_t))
        for s, e in pieces:
            if e - s <= _EPS:
                continue
            mid = (s + e) / 2
            center = (mid, at, WALL_HEIGHT / 2) if along == "x" else (at, mid, WALL_HEIGHT / 2)
            size = (e - s, WALL_THICKNESS, WALL_HEIGHT) if along == "x" else (WALL_THICKNESS, e - s, WALL_HEIGHT)
            boxes.append((center, size))
    return boxes
