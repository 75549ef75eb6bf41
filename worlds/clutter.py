"""Small objects all over a home: on tops, inside storage, under covers, nested in containers.

Each room gets objects in proportion to its floor area, mostly of categories that belong in a room
of its kind (cereal in the kitchen, a toothbrush in the bathroom). An object goes on a surface:
a furniture top, a storage slot (relation 'inside', with the slot's name), the floor by a wall, or
the inside of a container object (a box, a bowl; relation 'inside' with the container as parent),
which may itself sit in a drawer, so objects nest several levels deep. Some objects are hidden under
a cover (a towel laid over them, a bowl or box upturned on them: relation 'under'). Floor objects
keep out of doorways and of the clear zones in front of furniture.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worlds.floorplan import WALL_THICKNESS
from worlds.fronts import slot_box
from worlds.furnish import PASSAGE, against_wall
from worlds.things import Furniture, Item, Rect, half_extents, rect_gap, rects_overlap, shrink
from worlds.vocabulary import COLOURS, CONTAINERS, COVERS, NO_TOP, OBJECT_ROOMS, OBJECTS, room_kind

#: Objects per square metre of floor, drawn per room.
DENSITY = (0.22, 0.32)
#: Chance that an object suits its room's kind; the rest are drawn from the whole vocabulary.
SUITED_PROBABILITY = 0.8
#: What one placement puts down: a single object, a container with things in it, a covered object.
GROUPS = {"single": 0.62, "container": 0.24, "cover": 0.14}
#: Where a single object goes, by surface kind.
SURFACE_WEIGHTS = {"on": 0.45, "inside": 0.4, "floor": 0.15}
#: The deepest chain of containers (a ring in a jewelry box in a box in a drawer is three).
MAX_NESTING = 3
#: Containers with a lid hide what is in them; open ones (a bowl, a basket) let it stick out.
OPEN_CONTAINERS = ("bowl", "basket")
#: Objects only ever put on a furniture top, and the furniture they stand on.
TOP_ONLY = {"table lamp": ("nightstand", "desk", "table", "drawer chest", "cabinet", "shelf", "coffee table")}
LAMP_ON_PROBABILITY = 0.5
_WALL = 0.01
_GAP = 0.02
_TRIES = 25


@dataclass(frozen=True)
class Surface:
    """Where objects can stand: ``area`` at height ``z``, for objects up to ``headroom`` tall."""

    relation: str
    parent: int | None
    slot: str | None
    room: str
    area: Rect
    z: float
    headroom: float


def place_objects(
    rng: np.random.Generator, rooms: dict[str, Rect], furniture: list[Furniture], keep_out: list[Rect], first_id: int
) -> list[Item]:
    """Objects for every room, ids from ``first_id``; ``keep_out`` is where no floor object may stand.

    Args:
        rng: the draws' generator.
        rooms: each room's rectangle.
        furniture: the furniture placed.
        keep_out: where no floor object may stand.
        first_id: the first object's id.

    Returns:
        The objects.
    """
    placer = _Placer(rng, furniture, keep_out, first_id)
    for name, rect in rooms.items():
        pieces = [f for f in furniture if f.room == name]
        surfaces = _surfaces(name, rect, pieces)
        target = len(placer.items) + max(1, round((rect[2] - rect[0]) * (rect[3] - rect[1]) * rng.uniform(*DENSITY)))
        for _ in range(4 * (target - len(placer.items))):
            if len(placer.items) >= target:
                break
            group = str(rng.choice(list(GROUPS), p=list(GROUPS.values())))
            placer.group(group, surfaces, room_kind(name), target)
    return placer.items


def _surfaces(room: str, rect: Rect, pieces: list[Furniture]) -> list[Surface]:
    surfaces = [Surface("floor", None, None, room, shrink(rect, WALL_THICKNESS / 2 + 0.03), 0.0, float("inf"))]
    for piece in pieces:
        if piece.category not in NO_TOP:
            area = shrink(piece.footprint, 0.03)
            surfaces.append(Surface("on", piece.instance_id, None, room, area, piece.top_z, float("inf")))
        for slot in piece.storage.slots if piece.storage is not None else ():
            (cx, cy, cz), (sx, sy, sz) = slot_box(piece, slot.name)
            area = (cx - sx / 2, cy - sy / 2, cx + sx / 2, cy + sy / 2)
            surfaces.append(Surface("inside", piece.instance_id, slot.name, room, area, cz - sz / 2, sz))
    return surfaces


class _Placer:
    """Puts objects down one group at a time, remembering what stands where."""

    def __init__(self, rng: np.random.Generator, furniture: list[Furniture], keep_out: list[Rect], first_id: int):
        self.rng = rng
        self.furniture = furniture
        self._category_of = {f.instance_id: f.category for f in furniture}
        self.keep_out = keep_out
        self.next_id = first_id
        self.items: list[Item] = []
        self._on: dict[tuple[str, int | None, str | None], list[Rect]] = {}
        self._floor: list[Rect] = []

    def group(self, group: str, surfaces: list[Surface], kind: str, target: int) -> None:
        rng = self.rng
        if group == "cover":
            cover = str(rng.choice(COVERS))
            surface = self._pick_surface(surfaces, ("on", "floor", "inside"))
            if surface is not None:
                self._cover(cover, surface, kind)
            return
        if group == "container":
            container = self._category(kind, CONTAINERS)
            surface = self._pick_surface(surfaces, ("on", "inside", "floor"))
            item = None if surface is None else self._put(container, surface)
            if item is not None:
                self._fill(item, kind, 1, target)
            return
        category = self._category(kind, tuple(OBJECTS))
        if category in TOP_ONLY:
            tops = [s for s in surfaces if s.relation == "on" and self._category_of[s.parent] in TOP_ONLY[category]]
            surface = tops[int(rng.integers(len(tops)))] if tops else None
        else:
            surface = self._pick_surface(surfaces, tuple(SURFACE_WEIGHTS))
        if surface is not None:
            self._put(category, surface)

    def _category(self, kind: str, pool: tuple[str, ...]) -> str:
        suited = [c for c in pool if kind in OBJECT_ROOMS[c]]
        if suited and self.rng.random() < SUITED_PROBABILITY:
            pool = tuple(suited)
        return str(pool[int(self.rng.integers(len(pool)))])

    def _pick_surface(self, surfaces: list[Surface], relations: tuple[str, ...]) -> Surface | None:
        present = [r for r in relations if any(s.relation == r for s in surfaces)]
        if not present:
            return None
        weights = np.array([SURFACE_WEIGHTS[r] for r in present])
        relation = present[int(self.rng.choice(len(present), p=weights / weights.sum()))]
        options = [s for s in surfaces if s.relation == relation]
        return options[int(self.rng.integers(len(options)))]

    def _fill(self, container: Item, kind: str, depth: int, target: int) -> None:
        """1-3 things in ``container``; a container among them is filled in turn, up to `MAX_NESTING`."""
        hx, hy, hz = container.half_extents
        x, y, z = container.center
        height = 2 * hz - 2 * _WALL
        headroom = 3 * height if container.category in OPEN_CONTAINERS else height
        area = (x - hx + _WALL, y - hy + _WALL, x + hx - _WALL, y + hy - _WALL)
        inside = Surface("inside", container.instance_id, None, container.room, area, z - hz + _WALL, headroom)
        for _ in range(int(self.rng.integers(1, 4))):
            if len(self.items) >= target:
                return
            fitting = tuple(c for c in OBJECTS if c not in TOP_ONLY and _fits(c, inside))
            if not fitting:
                return
            item = self._put(self._category(kind, fitting), inside)
            if item is not None and item.category in CONTAINERS and depth < MAX_NESTING:
                self._fill(item, kind, depth + 1, target)

    def _cover(self, cover: str, surface: Surface, kind: str) -> None:
        """A small object with ``cover`` over it: laid on it (a towel) or upturned on it (a bowl, a box)."""
        chx, chy, chz = half_extents(cover)
        towel = cover == "towel"
        room_x, room_y = chx - 0.03, chy - 0.03
        limit = min(0.12, surface.headroom - 2 * chz) if towel else 2 * chz - 2 * _WALL
        hidden = tuple(c for c in OBJECTS if c not in TOP_ONLY and c not in COVERS and _fits(
            c, Surface("under", None, None, "", (-room_x, -room_y, room_x, room_y), 0.0, limit)))
        spot = self._spot(cover, surface) if hidden else None
        if spot is None:
            return
        category = self._category(kind, hidden)
        x, y = spot
        hz = half_extents(category)[2]
        cover_z = surface.z + 2 * hz + chz if towel else surface.z + chz
        parent = self._add(cover, surface, (x, y, cover_z), {} if towel else {"upturned": True})
        self._add(category, Surface("under", parent.instance_id, None, surface.room, surface.area, surface.z, limit),
                  (x, y, surface.z + hz), {})

    def _put(self, category: str, surface: Surface) -> Item | None:
        spot = self._spot(category, surface)
        if spot is None:
            return None
        return self._add(category, surface, (*spot, surface.z + half_extents(category)[2]), {})

    def _spot(self, category: str, surface: Surface) -> tuple[float, float] | None:
        """A free (x, y) for ``category`` on ``surface``, or None after `_TRIES` draws."""
        if not _fits(category, surface):
            return None
        hx, hy, _ = half_extents(category)
        key = (surface.relation, surface.parent, surface.slot)
        taken = self._on.setdefault(key, [])
        for _ in range(_TRIES):
            if surface.relation == "floor":
                side = int(self.rng.integers(4))
                length, depth = (2 * hx, 2 * hy) if side < 2 else (2 * hy, 2 * hx)
                footprint = against_wall(self.rng, surface.area, side, length, depth)
                if footprint is None or not self._floor_free(footprint, surface.room):
                    continue
            else:
                a = surface.area
                x = round(float(self.rng.uniform(a[0] + hx, a[2] - hx)), 3)
                y = round(float(self.rng.uniform(a[1] + hy, a[3] - hy)), 3)
                footprint = (x - hx, y - hy, x + hx, y + hy)
            if any(rect_gap(footprint, other) < _GAP for other in taken):
                continue
            taken.append(footprint)
            if surface.relation == "floor":
                self._floor.append(footprint)
            return (round((footprint[0] + footprint[2]) / 2, 3), round((footprint[1] + footprint[3]) / 2, 3))
        return None

    def _floor_free(self, footprint: Rect, room: str) -> bool:
        if any(rects_overlap(footprint, zone) for zone in self.keep_out):
            return False
        if any(f.room == room and rect_gap(footprint, f.footprint) < PASSAGE for f in self.furniture):
            return False
        return all(rect_gap(footprint, other) >= PASSAGE for other in self._floor)

    def _add(self, category: str, surface: Surface, center: tuple[float, float, float], attributes: dict) -> Item:
        colour = str(list(COLOURS)[int(self.rng.integers(len(COLOURS)))])
        state = {"power": "on" if self.rng.random() < LAMP_ON_PROBABILITY else "off"} if category in TOP_ONLY else {}
        item = Item(self.next_id, category, colour, surface.room, center, surface.relation, surface.parent,
                    surface.slot, attributes, state)
        self.next_id += 1
        self.items.append(item)
        return item


def _fits(category: str, surface: Surface) -> bool:
    hx, hy, hz = half_extents(category)
    a = surface.area
    return 2 * hx <= a[2] - a[0] and 2 * hy <= a[3] - a[1] and 2 * hz <= surface.headroom
