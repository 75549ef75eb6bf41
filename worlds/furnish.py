"""Putting furniture into rooms: the right pieces for the room, against walls, out of the way.

Every piece stands with its back to a wall and its front facing into the room. A room gets its
kind's essentials first (a kitchen its counter, fridge and stove), then more pieces suited to it,
as many as its floor area carries. Pieces keep a robot-wide gap between them (or stand flush side
by side along one wall, like a kitchen run), stay out of every doorway's clear zone, and keep a
clear zone in front of them: for storage as deep as its doors, drawers and flaps reach when fully
open plus room for the robot to stand, so every door can open and be reached. Curtains hang on
outside walls only. Joint states and switches are drawn here too: most parts closed, some open.
"""

from __future__ import annotations

import math

import numpy as np

from worlds.floorplan import WALL_THICKNESS
from worlds.fronts import stand_point, use_zone, world_size
from worlds.storage import StorageModel, storage_model
from worlds.things import Furniture, Rect, Room, rect_gap, rects_overlap, shrink
from worlds.vocabulary import APPLIANCES, COLOURS, ESSENTIALS, FURNITURE, STORAGE_CATEGORIES

FURNITURE_COLOURS = ("white", "black", "brown", "grey")
#: Free depth kept in front of each doorway, on both sides of the wall.
DOOR_CLEARANCE = 0.8
#: Gap kept between furniture pieces, and between furniture and floor objects: a robot fits through.
PASSAGE = 0.7
#: Depth kept free in front of every piece beyond what its parts sweep: where the robot stands.
STAND = 0.6
#: Pieces per square metre of floor, drawn per room, and the most one room gets.
DENSITY = (0.12, 0.2)
MAX_PIECES = 9
#: Chance that a storage part stands open, and that a switch is on / a curtain closed.
OPEN_PROBABILITY = 0.12
POWER_ON_PROBABILITY = {"lamp": 0.5, "tv": 0.35, "stove": 0.25}
CURTAIN_CLOSED_PROBABILITY = 0.4
#: Furniture a room has one of at most.
SINGLE = frozenset({"bed", "sofa", "tv", "fridge", "stove", "dishwasher", "bathtub", "toilet", "washing machine",
                    "workbench", "desk", "wardrobe", "table", "coffee table"})
#: Sides of a room: 0 south (y min), 1 north, 2 west (x min), 3 east. A piece against a side faces:
FACING = (math.pi / 2, -math.pi / 2, 0.0, math.pi)
#: A piece that goes beside another (a nightstand by the bed) or across the room from it (a TV
#: facing the sofa) is tried there first; pieces that form runs along a wall often stand flush.
BESIDE = {"nightstand": "bed", "dishwasher": "counter", "stove": "counter", "armchair": "sofa"}
OPPOSITE = {"tv": "sofa"}
RUNS = frozenset({"counter", "cabinet", "dishwasher", "stove", "fridge", "shelf", "drawer chest", "wardrobe",
                  "washing machine"})
#: Pieces that stand free in the room, and how often (otherwise against a wall like the rest).
MIDDLE = {"coffee table": 1.0, "table": 0.7}
_OPPOSITE_SIDE = (1, 0, 3, 2)
_GAP_TO_WALL = 0.02
_FLUSH_PROBABILITY = 0.5
_PARTNER_PROBABILITY = 0.8
_TRIES = 40


def furnish_room(
    rng: np.random.Generator, room: Room, outside: set[int], zones: list[Rect], first_id: int
) -> list[Furniture] | None:
    """Furniture for ``room`` (ids from ``first_id``); None if its first essential does not fit
    (a bedroom without a bed is no bedroom), in which case the home is drawn again.

    ``outside`` holds the sides of the room on the home's outline (0 south, 1 north, 2 west,
    3 east), where curtains may hang; ``zones`` are rectangles nothing may stand in.

    Args:
        rng: the draws' generator.
        room: the room.
        outside: its sides on the outline.
        zones: where nothing may stand.
        first_id: the first piece's id.

    Returns:
        The pieces, or None.
    """
    placed: list[Furniture] = []
    for k, category in enumerate(_wanted(rng, room)):
        piece = _place(rng, category, room, outside, zones, placed, first_id + len(placed))
        if piece is None and k == 0:
            return None
        if piece is not None:
            placed.append(piece)
    return placed


def clear_zone(piece: Furniture) -> Rect:
    """The rectangle in front of ``piece`` kept clear: what its parts sweep and room to stand.

    Args:
        piece: the furniture piece.

    Returns:
        The rectangle.
    """
    size = world_size(piece.size, piece.facing)  # back to the piece's own (width, depth, height)
    return use_zone(piece.center, piece.facing, size, piece.storage, _stand(piece.category))


def _stand(category: str) -> float:
    return 0.0 if category == "curtain" else STAND


def _wanted(rng: np.random.Generator, room: Room) -> list[str]:
    """The categories to try: every essential, then others suited to the room up to `DENSITY`."""
    count = int(np.clip(round(room.area_m2 * rng.uniform(*DENSITY)), 2, MAX_PIECES))
    wanted = list(ESSENTIALS[room.kind])
    suited = sorted(name for name, (_, kinds) in FURNITURE.items() if room.kind in kinds)
    while len(wanted) < count:
        options = [name for name in suited if name not in SINGLE or name not in wanted]
        wanted.append(options[int(rng.integers(len(options)))])
    return wanted


def _place(
    rng: np.random.Generator,
    category: str,
    room: Room,
    outside: set[int],
    zones: list[Rect],
    placed: list[Furniture],
    instance_id: int,
) -> Furniture | None:
    model = storage_model(category.replace(" ", "_"), rng) if category in STORAGE_CATEGORIES else None
    size = model.size if model is not None else _size(rng, category)
    inner = shrink(room.rect, WALL_THICKNESS / 2)
    for _ in range(_TRIES):
        spot = _candidate(rng, category, size, inner, outside, placed)
        if spot is None:
            continue
        footprint, facing = spot
        center = ((footprint[0] + footprint[2]) / 2, (footprint[1] + footprint[3]) / 2, size[2] / 2)
        zone = use_zone(center, facing, size, model, _stand(category))
        if not _fits(footprint, zone, inner, zones, placed, facing):
            continue
        return Furniture(
            instance_id, category, _colour(rng, category), room.name, center, world_size(size, facing), facing,
            model, _joints(rng, model), _state(rng, category),
        )
    return None


def _candidate(
    rng: np.random.Generator, category: str, size: tuple[float, float, float], inner: Rect, outside: set[int],
    placed: list[Furniture],
) -> tuple[Rect, float] | None:
    """A footprint and facing to try: beside or facing a partner, in the middle, or by a wall."""
    partner = next((f for f in placed if f.category == BESIDE.get(category)), None)
    opposite = next((f for f in placed if f.category == OPPOSITE.get(category)), None)
    if category in MIDDLE and rng.random() < MIDDLE[category]:
        return _in_middle(rng, category, size, inner, placed)
    start = None
    if partner is not None and rng.random() < _PARTNER_PROBABILITY:
        side = FACING.index(partner.facing)
        start = _flush_start(rng, [partner], side, size[0])
    elif opposite is not None and rng.random() < _PARTNER_PROBABILITY:
        side = _OPPOSITE_SIDE[FACING.index(opposite.facing)]
    else:
        sides = sorted(outside) if category == "curtain" else [0, 1, 2, 3]
        if not sides:
            return None
        side = sides[int(rng.integers(len(sides)))]
        run = [f for f in placed if f.facing == FACING[side] and f.category in RUNS] if category in RUNS else []
        start = _flush_start(rng, run, side, size[0]) if run and rng.random() < _FLUSH_PROBABILITY else None
    footprint = against_wall(rng, inner, side, size[0], size[1], start)
    return None if footprint is None else (footprint, FACING[side])


def _in_middle(
    rng: np.random.Generator, category: str, size: tuple[float, float, float], inner: Rect, placed: list[Furniture]
) -> tuple[Rect, float] | None:
    """A free-standing footprint a robot can walk all round: a coffee table in front of the sofa,
    a table anywhere in the open."""
    sofa = next((f for f in placed if f.category == "sofa"), None)
    if category == "coffee table" and sofa is not None:
        x, y = stand_point(sofa, PASSAGE + size[1] / 2)
        facing = sofa.facing
    else:
        facing = FACING[int(rng.integers(4))]
        w, d, _ = world_size(size, facing)
        x0, y0, x1, y1 = shrink(inner, PASSAGE)
        if x1 - x0 < w or y1 - y0 < d:
            return None
        x, y = rng.uniform(x0 + w / 2, x1 - w / 2), rng.uniform(y0 + d / 2, y1 - d / 2)
    w, d, _ = world_size(size, facing)
    footprint = (round(x - w / 2, 2), round(y - d / 2, 2), round(x - w / 2, 2) + w, round(y - d / 2, 2) + d)
    return (footprint, facing) if _inside(footprint, shrink(inner, PASSAGE)) else None


def _size(rng: np.random.Generator, category: str) -> tuple[float, float, float]:
    width, depth, height = FURNITURE[category][0]
    if category == "curtain":  # curtains are as wide as their window
        width = round(rng.uniform(1.2, 2.2), 2)
    return (width, depth, height)


def _fits(
    footprint: Rect, zone: Rect, inner: Rect, zones: list[Rect], placed: list[Furniture], facing: float
) -> bool:
    if not (_inside(footprint, inner) and _inside(zone, inner)):
        return False
    if any(rects_overlap(footprint, z) for z in zones):
        return False
    for other in placed:
        gap = rect_gap(footprint, other.footprint)
        flush = other.facing == facing and gap < 1e-6 and not rects_overlap(footprint, other.footprint)
        if gap < PASSAGE and not flush:
            return False
        if rects_overlap(zone, other.footprint) or rects_overlap(clear_zone(other), footprint):
            return False
    return True


def _flush_start(rng: np.random.Generator, neighbours: list[Furniture], side: int, length: float) -> float:
    """Where along the wall a piece of ``length`` starts so that it stands flush beside a neighbour."""
    other = neighbours[int(rng.integers(len(neighbours)))].footprint
    lo, hi = (other[0], other[2]) if side < 2 else (other[1], other[3])
    return hi if rng.random() < 0.5 else lo - length


def against_wall(
    rng: np.random.Generator, inner: Rect, side: int, length: float, depth: float, start: float | None = None
) -> Rect | None:
    """A footprint of ``length`` along wall ``side`` (0 south, 1 north, 2 west, 3 east), ``depth`` deep.

    It starts at ``start`` along the wall, or at a random place when None.

    Args:
        rng: the draws' generator.
        inner: the room's inner rectangle.
        side: the wall.
        length: the footprint's length along it.
        depth: its depth.
        start: where it starts along the wall, or None.

    Returns:
        The footprint, or None when it does not fit.
    """
    x0, y0, x1, y1 = inner
    along_lo, along_hi = (x0, x1) if side < 2 else (y0, y1)
    room = along_hi - along_lo - 2 * _GAP_TO_WALL - length
    if room < 0:
        return None
    if start is None:
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


def _colour(rng: np.random.Generator, category: str) -> str:
    palette = [c for c in COLOURS if c != "black"] if category == "curtain" else FURNITURE_COLOURS
    return str(palette[int(rng.integers(len(palette)))])


def _joints(rng: np.random.Generator, model: StorageModel | None) -> dict[str, float]:
    """Each part's joint state: closed, or with `OPEN_PROBABILITY` open part or all of the way."""
    if model is None:
        return {}
    joints = {}
    for part in model.parts:  # opened part of the way, rounded down to stay within the limit
        opened = rng.random() < OPEN_PROBABILITY
        joints[part.name] = math.floor(rng.uniform(0.35, 1.0) * part.upper * 1000) / 1000 if opened else 0.0
    return joints


def _state(rng: np.random.Generator, category: str) -> dict[str, str]:
    if category in APPLIANCES:
        return {"power": "on" if rng.random() < POWER_ON_PROBABILITY[category] else "off"}
    if category == "curtain":
        return {"curtain": "closed" if rng.random() < CURTAIN_CLOSED_PROBABILITY else "open"}
    return {}
