"""A home as plain data, and the seeded generator that makes one.

`generate_home` draws everything from one ``numpy.random.Generator`` seeded with the seed, so the
same seed gives the same home on any machine. A draw that fails (a room too small to cut, rooms
that cannot all be joined by doors, a room or a storage front a robot could not reach) is thrown
away and the generator draws again from the same stream, which keeps it deterministic. No PyBullet
here: the scene is built from this data elsewhere, and worlds.spec writes it as JSON.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from worlds.clutter import place_objects
from worlds.floorplan import Door, pick_doors, shared_edges, split_floor, wall_boxes
from worlds.freespace import free_space
from worlds.fronts import stand_point, storage_obstacles
from worlds.furnish import DOOR_CLEARANCE, STAND, clear_zone, furnish_room
from worlds.robot import ROBOT_RADIUS
from worlds.storage_placement import home_part_labels
from worlds.things import Doorway, Furniture, Item, Label, Rect, Room, Wall
from worlds.vocabulary import COLOURS, room_name

log = logging.getLogger(__name__)

ROOM_COUNT = (4, 10)
AREA_RANGE = (60.0, 300.0)
#: The least floor a room may have on average; fewer rooms are asked for in a smaller home.
MIN_AREA_PER_ROOM = 8.0
#: Floor area a room gets on average when only the room count is given.
AREA_PER_ROOM = (14.0, 30.0)
#: Floor tints; never white or black. With more rooms than tints, tints repeat.
FLOOR_COLOURS = tuple(c for c in COLOURS if c not in ("white", "black"))
#: Every home has these; the rest are drawn from `EXTRA_ROOMS` by weight without replacement (a
#: kind listed twice may be drawn twice: a second bedroom, then a third).
BASE_ROOMS = ("kitchen", "living room", "bedroom", "bathroom")
EXTRA_ROOMS = (
    ("dining room", 1.0), ("office", 0.9), ("hallway", 1.0), ("bedroom", 0.9), ("laundry room", 0.6),
    ("garage", 0.5), ("bathroom", 0.6), ("bedroom", 0.4),
)
#: Typical floor area of each kind; bigger kinds get the bigger rectangles of the plan.
TYPICAL_AREA = {
    "living room": 28.0, "garage": 24.0, "kitchen": 14.0, "dining room": 14.0, "bedroom": 14.0, "office": 10.0,
    "bathroom": 6.0, "laundry room": 6.0,
}
_ATTEMPTS = 300


@dataclass(frozen=True)
class HomeSpec:
    """Everything in one home. Instance ids run 1..N over rooms (floors), walls, furniture and
    objects; storage parts follow (worlds.storage_placement.home_storage), two ids per part and its handle."""

    seed: int
    rooms: tuple[Room, ...]
    doorways: tuple[Doorway, ...]
    walls: tuple[Wall, ...]
    furniture: tuple[Furniture, ...]
    objects: tuple[Item, ...]

    @property
    def area_m2(self) -> float:
        return sum(room.area_m2 for room in self.rooms)

    @property
    def bounds(self) -> Rect:
        """The outline on the wall centre lines: (xmin, ymin, xmax, ymax)."""
        rects = [room.rect for room in self.rooms]
        return (min(r[0] for r in rects), min(r[1] for r in rects),
                max(r[2] for r in rects), max(r[3] for r in rects))

    def labels(self) -> dict[int, Label]:
        """The ground-truth label of every instance id, storage parts and handles included.

        Returns:
            The labels by id.
        """
        things = (*self.rooms, *self.walls, *self.furniture, *self.objects)
        return {**{thing.instance_id: thing.label() for thing in things}, **home_part_labels(self)}

    def obstacles(self) -> list[Rect]:
        """Footprints a robot on the floor can bump into: walls, furniture with its handles and open
        parts, and objects on the floor (what is inside or under them stays within them).

        Returns:
            The footprints.
        """
        return [
            *(w.footprint for w in self.walls),
            *(f.footprint for f in self.furniture),
            *(rect for f in self.furniture for rect in storage_obstacles(f)),
            *(o.footprint for o in self.objects if o.relation == "floor"),
        ]

    def room_at(self, x: float, y: float) -> str | None:
        """The name of the room holding (x, y); None outside every room.

        Args:
            x: the point's x (m).
            y: the point's y (m).

        Returns:
            The name, or None.
        """
        return next((room.name for room in self.rooms if room.contains(x, y)), None)

    def to_dict(self) -> dict[str, Any]:
        """The home's scene spec (worlds.spec, the versioned JSON document).

        Returns:
            The spec.
        """
        from worlds.spec import dump_spec  # the spec module builds on this one

        return dump_spec(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> HomeSpec:
        """A home from its scene spec, checked field by field (worlds.spec.SpecError when malformed).

        Args:
            data: the scene spec.

        Returns:
            The home.

        Raises:
            SpecError: the spec is malformed.
        """
        from worlds.spec import load_spec

        return load_spec(data)


def generate_home(seed: int, n_rooms: int | None = None, area_m2: float | None = None) -> HomeSpec:
    """A home of ``n_rooms`` rooms (4-10) and about ``area_m2`` square metres (60-300), every room
    and every storage front reachable by the robot. Either may be None: it is drawn from the seed.

    Args:
        seed: the home's seed (≥ 0).
        n_rooms: the rooms, or None.
        area_m2: the floor area, or None.

    Returns:
        The home.

    Raises:
        ValueError: a seed, room count or area out of range.
    """
    if seed < 0:
        raise ValueError(f"seed: {seed} must not be negative")
    if n_rooms is not None and not ROOM_COUNT[0] <= n_rooms <= ROOM_COUNT[1]:
        raise ValueError(f"n_rooms: {n_rooms} is not in {ROOM_COUNT[0]}..{ROOM_COUNT[1]}")
    if area_m2 is not None and not (math.isfinite(area_m2) and AREA_RANGE[0] <= area_m2 <= AREA_RANGE[1]):
        raise ValueError(f"area_m2: {area_m2} is not in {AREA_RANGE[0]:g}..{AREA_RANGE[1]:g}")
    if n_rooms is not None and area_m2 is not None and area_m2 < n_rooms * MIN_AREA_PER_ROOM:
        raise ValueError(
            f"area_m2: {area_m2:g} is too small for {n_rooms} rooms (at least {MIN_AREA_PER_ROOM:g} m² a room)")
    rng = np.random.default_rng(seed)
    count, area = _size(rng, n_rooms, area_m2)
    for attempt in range(_ATTEMPTS):
        home = _draw(rng, seed, count, area)
        if home is not None:
            log.debug("home %d: drawn on attempt %d", seed, attempt + 1)
            return home
    raise RuntimeError(f"seed {seed}: no valid home in {_ATTEMPTS} draws")


def _size(rng: np.random.Generator, n_rooms: int | None, area_m2: float | None) -> tuple[int, float]:
    """The room count and floor area: as given, or drawn to suit each other."""
    if n_rooms is None and area_m2 is not None:
        most = min(ROOM_COUNT[1], int(area_m2 // MIN_AREA_PER_ROOM))
        n_rooms = int(np.clip(round(area_m2 / rng.uniform(*AREA_PER_ROOM)), ROOM_COUNT[0], most))
    if n_rooms is None:
        n_rooms = int(rng.integers(ROOM_COUNT[0], ROOM_COUNT[1] + 1))
    if area_m2 is None:
        low = max(AREA_RANGE[0], n_rooms * MIN_AREA_PER_ROOM)
        area_m2 = float(np.clip(n_rooms * rng.uniform(*AREA_PER_ROOM), low, AREA_RANGE[1]))
    return n_rooms, float(area_m2)


def room_kinds(rng: np.random.Generator, count: int) -> list[str]:
    """The kinds of a home's ``count`` rooms: `BASE_ROOMS` and extras drawn by weight.

    Args:
        rng: the draws' generator.
        count: the rooms.

    Returns:
        The kinds.
    """
    weights = np.array([weight for _, weight in EXTRA_ROOMS])
    drawn = rng.choice(len(EXTRA_ROOMS), size=count - len(BASE_ROOMS), replace=False, p=weights / weights.sum())
    return [*BASE_ROOMS, *(EXTRA_ROOMS[int(i)][0] for i in drawn)]


def _assign(
    rng: np.random.Generator, kinds: list[str], rects: list[Rect], hallway: int | None
) -> list[tuple[str, str]]:
    """(name, kind) for each rectangle: the hallway its strip, bigger kinds the bigger rectangles."""
    rest = [k for k in kinds if k != "hallway"]
    noisy = [TYPICAL_AREA[k] * rng.lognormal(0.0, 0.25) for k in rest]
    by_size = [rest[i] for i in np.argsort(noisy, kind="stable")[::-1]]
    indices = [i for i in range(len(rects)) if i != hallway]
    areas = [(rects[i][2] - rects[i][0]) * (rects[i][3] - rects[i][1]) for i in indices]
    order = [indices[i] for i in np.argsort(areas, kind="stable")[::-1]]
    kind_of = dict(zip(order, by_size))
    if hallway is not None:
        kind_of[hallway] = "hallway"
    named = []
    for i in range(len(rects)):  # ordinals follow size: the biggest bedroom is 'bedroom'
        kind = kind_of[i]
        rank = sorted((j for j in kind_of if kind_of[j] == kind), key=lambda j: (-_area(rects[j]), j)).index(i)
        named.append((room_name(kind, rank), kind))
    return named


def _area(rect: Rect) -> float:
    return (rect[2] - rect[0]) * (rect[3] - rect[1])


def _draw(rng: np.random.Generator, seed: int, count: int, area: float) -> HomeSpec | None:
    kinds = room_kinds(rng, count)
    plan = split_floor(rng, count, area, "hallway" in kinds)
    if plan is None:
        return None
    outline, rects, hallway = plan
    edges = shared_edges(rects)
    doors = pick_doors(rng, count, edges, hallway)
    if doors is None:
        return None
    named = _assign(rng, kinds, rects, hallway)
    tints = [FLOOR_COLOURS[int(i)] for i in rng.permutation(len(FLOOR_COLOURS))]
    rooms = tuple(Room(i + 1, *named[i], rects[i], tints[i % len(tints)]) for i in range(count))
    doorways = tuple(_doorway(door, rooms) for door in doors)
    next_id = count + 1
    walls = tuple(Wall(next_id + i, c, s) for i, (c, s) in enumerate(wall_boxes(outline, edges, doors)))
    next_id += len(walls)
    zones = [d.clear_zone(DOOR_CLEARANCE) for d in doorways]
    furniture: list[Furniture] = []
    for room in rooms:
        pieces = furnish_room(rng, room, _outside(room.rect, outline), zones, next_id)
        if pieces is None:
            return None
        furniture += pieces
        next_id += len(pieces)
    bare = HomeSpec(seed, rooms, doorways, walls, tuple(furniture), ())
    if not _reachable(bare):
        return None
    keep_out = zones + [clear_zone(piece) for piece in furniture]
    objects = place_objects(rng, {r.name: r.rect for r in rooms}, furniture, keep_out, next_id)
    home = HomeSpec(seed, rooms, doorways, walls, tuple(furniture), tuple(objects))
    return home if _reachable(home) else None


def _outside(rect: Rect, outline: Rect) -> set[int]:
    """The sides of ``rect`` on the outline: 0 south, 1 north, 2 west, 3 east."""
    return {side for side, (a, b) in enumerate(((rect[1], outline[1]), (rect[3], outline[3]),
                                                (rect[0], outline[0]), (rect[2], outline[2]))) if abs(a - b) < 1e-6}


def _reachable(home: HomeSpec) -> bool:
    """Whether the robot disc reaches every room, and stands in front of every storage piece."""
    space = free_space(home, ROBOT_RADIUS)
    main = space.main_component()
    reached = set(np.unique(space.room_of_cell[space.components == main]).tolist()) - {-1}
    if main == 0 or reached != set(range(len(home.rooms))):
        return False
    for piece in home.furniture:
        if piece.storage is not None:
            row, col = space.cell_at(*stand_point(piece, STAND / 2))
            if space.components[row, col] != main:
                return False
    return True


def _doorway(door: Door, rooms: tuple[Room, ...]) -> Doorway:
    return Doorway((rooms[door.edge.a].name, rooms[door.edge.b].name), door.center, door.width, door.edge.along)
