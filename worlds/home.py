"""A home as plain data, and the seeded generator that makes one.

`generate_home` draws everything from one ``numpy.random.Generator`` seeded with the seed, so the
same seed gives the same home on any machine. A draw that fails (a room too small to cut, rooms
that cannot all be joined by doors, furniture that does not fit, a room a robot could not reach)
is thrown away and the generator draws again from the same stream, which keeps it deterministic.
No PyBullet here: the scene is built from this data elsewhere.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import Any

import numpy as np

from worlds.floorplan import Door, pick_doors, shared_edges, split_floor, wall_boxes
from worlds.freespace import reachable_rooms
from worlds.furnish import DOOR_CLEARANCE, place_furniture, place_objects
from worlds.robot import ROBOT_RADIUS
from worlds.things import Doorway, Furniture, Item, Label, Rect, Room, Wall, from_plain, to_plain
from worlds.vocabulary import ROOM_TYPES

log = logging.getLogger(__name__)

ROOM_COUNT = (3, 5)
#: Floor tints, one per room; never white or black, so furniture (white or black) stands out.
FLOOR_COLOURS = ("red", "green", "blue", "yellow", "orange", "purple")
_ATTEMPTS = 500


@dataclass(frozen=True)
class HomeSpec:
    """Everything that is in one home. Instance ids run 1..N over rooms (floors), walls, furniture, objects."""

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
        return (min(r[0] for r in rects), min(r[1] for r in rects), max(r[2] for r in rects), max(r[3] for r in rects))

    def labels(self) -> dict[int, Label]:
        """The ground-truth label of every instance id."""
        things = (*self.rooms, *self.walls, *self.furniture, *self.objects)
        return {thing.instance_id: thing.label() for thing in things}

    def obstacles(self) -> list[Rect]:
        """Footprints a robot on the floor can bump into: walls, furniture and objects on the floor."""
        return [
            *(w.footprint for w in self.walls),
            *(f.footprint for f in self.furniture),
            *(o.footprint for o in self.objects if o.on is None),
        ]

    def room_at(self, x: float, y: float) -> str | None:
        return next((room.name for room in self.rooms if room.contains(x, y)), None)

    def to_dict(self) -> dict[str, Any]:
        return {
            "seed": self.seed,
            "rooms": [to_plain(r) for r in self.rooms],
            "doorways": [to_plain(d) for d in self.doorways],
            "walls": [to_plain(w) for w in self.walls],
            "furniture": [to_plain(f) for f in self.furniture],
            "objects": [to_plain(o) for o in self.objects],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> HomeSpec:
        return cls(
            seed=int(data["seed"]),
            rooms=tuple(from_plain(Room, r) for r in data["rooms"]),
            doorways=tuple(from_plain(Doorway, d) for d in data["doorways"]),
            walls=tuple(from_plain(Wall, w) for w in data["walls"]),
            furniture=tuple(from_plain(Furniture, f) for f in data["furniture"]),
            objects=tuple(from_plain(Item, o) for o in data["objects"]),
        )


def generate_home(seed: int, n_rooms: int | None = None) -> HomeSpec:
    """A small home of ``n_rooms`` rooms (3-5; drawn from the seed when None), every room reachable."""
    if n_rooms is not None and not ROOM_COUNT[0] <= n_rooms <= ROOM_COUNT[1]:
        raise ValueError(f"n_rooms: {n_rooms} is not in {ROOM_COUNT[0]}..{ROOM_COUNT[1]}")
    if seed < 0:
        raise ValueError(f"seed: {seed} must not be negative")
    rng = np.random.default_rng(seed)
    count = n_rooms if n_rooms is not None else int(rng.integers(ROOM_COUNT[0], ROOM_COUNT[1] + 1))
    for attempt in range(_ATTEMPTS):
        home = _draw(rng, seed, count)
        if home is not None and len(reachable_rooms(home, ROBOT_RADIUS)) == count:
            log.debug("home %d: drawn on attempt %d", seed, attempt + 1)
            return home
    raise RuntimeError(f"seed {seed}: no valid home in {_ATTEMPTS} draws")


def _draw(rng: np.random.Generator, seed: int, count: int) -> HomeSpec | None:
    plan = split_floor(rng, count)
    if plan is None:
        return None
    outline, rects = plan
    edges = shared_edges(rects)
    doors = pick_doors(rng, count, edges)
    if doors is None:
        return None
    names = [str(n) for n in rng.choice(ROOM_TYPES, size=count, replace=False)]
    floor_colours = [str(c) for c in rng.choice(FLOOR_COLOURS, size=count, replace=False)]
    rooms = tuple(Room(i + 1, names[i], rects[i], floor_colours[i]) for i in range(count))
    doorways = tuple(_doorway(door, names) for door in doors)
    next_id = count + 1
    walls = tuple(Wall(next_id + i, c, s) for i, (c, s) in enumerate(wall_boxes(outline, edges, doors)))
    next_id += len(walls)
    zones = [d.clear_zone(DOOR_CLEARANCE) for d in doorways]
    furniture: list[Furniture] = []
    for room in rooms:
        pieces = place_furniture(rng, room.name, room.rect, zones, next_id)
        if pieces is None:
            return None
        furniture += pieces
        next_id += len(pieces)
    objects = place_objects(rng, {r.name: r.rect for r in rooms}, furniture, zones, next_id)
    if objects is None:
        return None
    return HomeSpec(seed, rooms, doorways, walls, tuple(furniture), tuple(objects))


def _doorway(door: Door, names: list[str]) -> Doorway:
    return Doorway((names[door.edge.a], names[door.edge.b]), door.center, door.width, door.edge.along)
