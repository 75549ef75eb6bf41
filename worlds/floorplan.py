"""Floor plans: a rectangle cut into rooms, doorways that connect them all, and the walls between.

The plan is a guillotine partition (each cut splits one rectangle in two), so every room edge is
either on the outline or shared with neighbours, and walls are exactly the outline plus the shared
edges. Doorways form a random spanning tree over rooms that share enough wall for a door (plus
a few extra doors), so every room is reachable by construction. A hallway, when the home has one,
is a strip across the whole plan that most doors open onto.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from worlds.things import Rect

WALL_THICKNESS = 0.1
WALL_HEIGHT = 2.5
MIN_ROOM_SIDE = 2.5
HALLWAY_WIDTH = (1.3, 1.7)
DOOR_WIDTH = (0.9, 1.1)
#: Wall left on each side of a doorway, so the door never sits in a corner.
DOOR_MARGIN = 0.45
#: Doors beyond the spanning tree, per room on average: they make loops through the home.
EXTRA_DOOR_RATE = 0.15
#: How much likelier a door onto the hub room (the hallway) is than any other, per candidate.
HUB_WEIGHT = 6.0
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


def split_floor(
    rng: np.random.Generator, n_rooms: int, area_m2: float, hallway: bool
) -> tuple[Rect, list[Rect], int | None] | None:
    """The outline of about ``area_m2``, its ``n_rooms`` rooms and the hallway's index; None if a cut failed.

    With a hallway, a 1.3-1.7 m strip runs across the whole plan first and the two halves on either
    side are cut into the other rooms, so most rooms open onto the hallway the way homes are built.

    Args:
        rng: the draws' generator.
        n_rooms: the rooms, the hallway included.
        area_m2: the floor area.
        hallway: whether one room is a hallway across the plan.

    Returns:
        The outline, the rooms' rectangles and the hallway's index, or None.
    """
    aspect = rng.uniform(1.0, 1.7)
    width = round(math.sqrt(area_m2 * aspect), 1)
    height = round(area_m2 / width, 1)
    outline = (0.0, 0.0, width, height)
    if not hallway:
        rects = _guillotine(rng, outline, n_rooms)
        return None if rects is None else (outline, rects, None)
    across_x = width >= height  # the hallway runs along the longer side
    depth = height if across_x else width
    strip = round(rng.uniform(*HALLWAY_WIDTH), 1)
    room = depth - strip - 2 * MIN_ROOM_SIDE
    if room < 0:
        return None
    lo_depth = MIN_ROOM_SIDE + round(rng.uniform(0.0, room), 1)
    if across_x:
        hall = (0.0, lo_depth, width, lo_depth + strip)
        halves = [(0.0, 0.0, width, lo_depth), (0.0, lo_depth + strip, width, height)]
    else:
        hall = (lo_depth, 0.0, lo_depth + strip, height)
        halves = [(0.0, 0.0, lo_depth, height), (lo_depth + strip, 0.0, width, height)]
    share = _area(halves[0]) / (_area(halves[0]) + _area(halves[1]))
    low_count = int(np.clip(round((n_rooms - 1) * share), 1, n_rooms - 2))
    low = _guillotine(rng, halves[0], low_count)
    high = _guillotine(rng, halves[1], n_rooms - 1 - low_count)
    if low is None or high is None:
        return None
    return outline, [hall, *low, *high], 0


def _area(rect: Rect) -> float:
    return (rect[2] - rect[0]) * (rect[3] - rect[1])


def _guillotine(rng: np.random.Generator, outline: Rect, count: int) -> list[Rect] | None:
    """``outline`` cut into ``count`` rooms, each cut across the longer side of a piece drawn by area."""
    rects = [outline]
    while len(rects) < count:
        areas = np.array([_area(r) for r in rects])
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
    return rects


def shared_edges(rects: list[Rect]) -> list[SharedEdge]:
    """Every stretch of wall of positive length that two rooms share.

    Args:
        rects: the rooms' rectangles.

    Returns:
        The shared edges.
    """
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


def pick_doors(
    rng: np.random.Generator, n_rooms: int, edges: list[SharedEdge], hub: int | None = None
) -> list[Door] | None:
    """A random spanning tree of doors over rooms, plus a few extra; None if rooms can't connect.

    Doors onto the ``hub`` room (the hallway) are preferred, so the hallway serves most rooms.

    Args:
        rng: the draws' generator.
        n_rooms: the rooms.
        edges: the walls they share.
        hub: the hallway's index, if any.

    Returns:
        The doors, or None.
    """
    capable = [e for e in edges if e.length >= DOOR_WIDTH[1] + 2 * DOOR_MARGIN]
    visited = {hub if hub is not None else int(rng.integers(n_rooms))}
    chosen: list[SharedEdge] = []
    while len(visited) < n_rooms:
        options = [e for e in capable if (e.a in visited) != (e.b in visited)]
        if not options:
            return None
        weights = np.array([HUB_WEIGHT if hub in (e.a, e.b) else 1.0 for e in options])
        edge = options[int(rng.choice(len(options), p=weights / weights.sum()))]
        chosen.append(edge)
        visited |= {edge.a, edge.b}
    rest = [e for e in capable if e not in chosen]
    extra = min(len(rest), int(rng.binomial(n_rooms, EXTRA_DOOR_RATE)))
    chosen += [rest[int(i)] for i in rng.choice(len(rest), size=extra, replace=False)]
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

    Args:
        outline: the home's outline.
        edges: the shared walls.
        doors: the doors.

    Returns:
        The boxes.
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
