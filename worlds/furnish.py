"""Putting furniture and small objects into rooms without blocking the way through.

Furniture stands with its back to a wall and its long side along it, keeps a robot-wide gap to
other furniture and stays out of every doorway's clear zone. Small objects rest on furniture tops
or on the floor against a wall, again out of the doorways and leaving room to pass furniture.
"""

from __future__ import annotations

import numpy as np

from worlds.floorplan import WALL_THICKNESS
from worlds.things import Furniture, Item, Rect, half_extents, rect_gap, rects_overlap, shrink
from worlds.vocabulary import COLOURS, FURNITURE, OBJECTS

#: Furniture is black or white, so a question about a colour in a room is about its small objects.
FURNITURE_COLOURS = ("white", "black")
#: Free depth kept in front of each doorway, on both sides of the wall.
DOOR_CLEARANCE = 0.8
#: Gap kept between furniture pieces, and between furniture and floor objects: a robot fits through.
PASSAGE = 0.7
OBJECT_COUNT = (10, 14)
ON_FURNITURE_PROBABILITY = 0.65
_GAP_TO_WALL = 0.02
_TRIES = 60


def _against_wall(rng: np.random.Generator, inner: Rect, side: int, length: float, depth: float) -> Rect | None:
    """A footprint of ``length`` along wall ``side`` (0 south, 1 north, 2 west, 3 east), ``depth`` deep."""
    x0, y0, x1, y1 = inner
    along_lo, along_hi = (x0, x1) if side < 2 else (y0, y1)
    room = along_hi - along_lo - 2 * _GAP_TO_WALL - length
    if room < 0:
        return None
    start = along_lo + _GAP_TO_WALL + round(rng.uniform(0.0, room), 2)
    if side == 0:
        return (start, y0 + _GAP_TO_WALL, start + length, y0 + _GAP_TO_WALL + depth)
    if side == 1:
        return (start, y1 - _GAP_TO_WALL - depth, start + length, y1 - _GAP_TO_WALL)
    if side == 2:
        return (x0 + _GAP_TO_WALL, start, x0 + _GAP_TO_WALL + depth, start + length)
    return (x1 - _GAP_TO_WALL - depth, start, x1 - _GAP_TO_WALL, start + length)


def _inside(rect: Rect, outer: Rect) -> bool:
    return rect[0] >= outer[0] and rect[1] >= outer[1] and rect[2] <= outer[2] and rect[3] <= outer[3]


def place_furniture(
    rng: np.random.Generator, room: str, rect: Rect, zones: list[Rect], first_id: int
) -> list[Furniture] | None:
    """One or two pieces suited to ``room`` against its walls; None if not even one fits."""
    inner = shrink(rect, WALL_THICKNESS / 2)
    suited = [name for name, (_, rooms) in FURNITURE.items() if room in rooms]
    count = min(len(suited), int(rng.integers(1, 3)))
    placed: list[Furniture] = []
    for category in rng.choice(suited, size=count, replace=False):
        (length, depth, height), _ = FURNITURE[str(category)]
        for _ in range(_TRIES):
            side = int(rng.integers(4))
            footprint = _against_wall(rng, inner, side, length, depth)
            if footprint is None or not _inside(footprint, inner):
                continue
            if any(rects_overlap(footprint, z) for z in zones):
                continue
            if any(rect_gap(footprint, f.footprint) < PASSAGE for f in placed):
                continue
            center = ((footprint[0] + footprint[2]) / 2, (footprint[1] + footprint[3]) / 2, height / 2)
            size = (footprint[2] - footprint[0], footprint[3] - footprint[1], height)
            colour = str(rng.choice(FURNITURE_COLOURS))
            placed.append(Furniture(first_id + len(placed), str(category), colour, room, center, size))
            break
    return placed or None


def place_objects(
    rng: np.random.Generator,
    rooms: dict[str, Rect],
    furniture: list[Furniture],
    zones: list[Rect],
    first_id: int,
) -> list[Item] | None:
    """10-14 coloured objects on furniture tops or on the floor by a wall; None if one can't fit."""
    count = int(rng.integers(OBJECT_COUNT[0], OBJECT_COUNT[1] + 1))
    names = sorted(rooms)
    items: list[Item] = []
    for k in range(count):
        category = str(rng.choice(list(OBJECTS)))
        colour = str(rng.choice(list(COLOURS)))
        for _ in range(_TRIES):
            room = names[int(rng.integers(len(names)))]
            tops = [f for f in furniture if f.room == room]
            if tops and rng.random() < ON_FURNITURE_PROBABILITY:
                spot = _on_top(rng, category, tops[int(rng.integers(len(tops)))], items)
            else:
                spot = _on_floor(rng, category, rooms[room], zones, [f for f in furniture if f.room == room], items)
            if spot is not None:
                center, on = spot
                items.append(Item(first_id + k, category, colour, room, center, on))
                break
        else:
            return None
    return items


def _on_top(
    rng: np.random.Generator, category: str, piece: Furniture, items: list[Item]
) -> tuple[tuple[float, float, float], int] | None:
    hx, hy, hz = half_extents(category)
    x0, y0, x1, y1 = shrink(piece.footprint, 0.03)
    if x1 - x0 < 2 * hx or y1 - y0 < 2 * hy:
        return None
    x = round(rng.uniform(x0 + hx, x1 - hx), 3)
    y = round(rng.uniform(y0 + hy, y1 - hy), 3)
    footprint = (x - hx, y - hy, x + hx, y + hy)
    if any(i.on == piece.instance_id and rect_gap(footprint, i.footprint) < 0.03 for i in items):
        return None
    return (x, y, piece.top_z + hz), piece.instance_id


def _on_floor(
    rng: np.random.Generator,
    category: str,
    rect: Rect,
    zones: list[Rect],
    pieces: list[Furniture],
    items: list[Item],
) -> tuple[tuple[float, float, float], None] | None:
    hx, hy, hz = half_extents(category)
    side = int(rng.integers(4))
    length, depth = (2 * hx, 2 * hy) if side < 2 else (2 * hy, 2 * hx)
    footprint = _against_wall(rng, shrink(rect, WALL_THICKNESS / 2 + 0.03), side, length, depth)
    if footprint is None:
        return None
    if any(rects_overlap(footprint, z) for z in zones):
        return None
    if any(rect_gap(footprint, f.footprint) < PASSAGE for f in pieces):
        return None
    if any(i.on is None and rect_gap(footprint, i.footprint) < PASSAGE for i in items):
        return None
    return ((footprint[0] + footprint[2]) / 2, (footprint[1] + footprint[3]) / 2, hz), None
