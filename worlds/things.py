"""The things a home is made of, as plain frozen data with ground-truth labels.

Everything stands on a flat floor at z = 0 inside an axis-aligned box (storage furniture is turned
to face its room by quarter turns, so it still fits one), and every question about free space
reduces to rectangles in the plane: a `Rect` is ``(xmin, ymin, xmax, ymax)`` in metres. Every
rendered thing has a stable ``instance_id`` and a label ``{"id", "category", "colour"}``:
the same label the camera reports for its pixels. A label says what the thing looks like, never
which room the generator put it in: no camera sees a room's name (a floor is just a floor). worlds.spec turns all of it into JSON and back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from worlds.storage import StorageModel
from worlds.vocabulary import OBJECTS

Rect = tuple[float, float, float, float]
Label = dict[str, Any]

WALL_COLOUR = "white"


def rect_gap(a: Rect, b: Rect) -> float:
    """Euclidean distance between two rectangles; 0 when they touch or overlap.

    Args:
        a: one rectangle.
        b: the other.

    Returns:
        The distance.
    """
    dx = max(a[0] - b[2], b[0] - a[2], 0.0)
    dy = max(a[1] - b[3], b[1] - a[3], 0.0)
    return math.hypot(dx, dy)


#: Overlaps thinner than this are rounding, not overlaps: pieces placed flush side by side touch.
OVERLAP_TOLERANCE = 1e-9


def rects_overlap(a: Rect, b: Rect) -> bool:
    """Whether two rectangles share interior area (touching edges do not count).

    Args:
        a: one rectangle.
        b: the other.

    Returns:
        Whether they overlap.
    """
    tol = OVERLAP_TOLERANCE
    return a[0] < b[2] - tol and b[0] < a[2] - tol and a[1] < b[3] - tol and b[1] < a[3] - tol


def point_rect_distance(x: float, y: float, rect: Rect) -> float:
    """Distance from a point to a rectangle; 0 inside it.

    Args:
        x: the point's x.
        y: the point's y.
        rect: the rectangle.

    Returns:
        The distance.
    """
    return rect_gap((x, y, x, y), rect)


def shrink(rect: Rect, margin: float) -> Rect:
    """A rectangle moved in by ``margin`` on every side.

    Args:
        rect: the rectangle.
        margin: how far in (negative: out).

    Returns:
        The rectangle.
    """
    return (rect[0] + margin, rect[1] + margin, rect[2] - margin, rect[3] - margin)


def box_footprint(center: tuple[float, ...], size: tuple[float, ...]) -> Rect:
    """The floor rectangle of a box of ``size`` centred at ``center``.

    Args:
        center: the box's centre.
        size: its size.

    Returns:
        The rectangle.
    """
    return (center[0] - size[0] / 2, center[1] - size[1] / 2, center[0] + size[0] / 2, center[1] + size[1] / 2)


def _label(instance_id: int, category: str, colour: str) -> Label:
    return {"id": instance_id, "category": category, "colour": colour}


@dataclass(frozen=True)
class Room:
    """A rectangular room of a ``kind`` (a `vocabulary.ROOM_TYPES` word) with a unique ``name``.

    The name is the kind for the first room of a kind and 'second bedroom', 'third bedroom' after
    that. Its floor is a thing of its own (category 'floor') with the room's id.
    """

    instance_id: int
    name: str
    kind: str
    rect: Rect
    floor_colour: str

    @property
    def area_m2(self) -> float:
        return (self.rect[2] - self.rect[0]) * (self.rect[3] - self.rect[1])

    @property
    def polygon(self) -> list[list[float]]:
        """Corners counter-clockwise from (xmin, ymin), on the wall centre lines."""
        x0, y0, x1, y1 = self.rect
        return [[x0, y0], [x1, y0], [x1, y1], [x0, y1]]

    def contains(self, x: float, y: float) -> bool:
        """Whether (x, y) lies in the room, its edges included.

        Args:
            x: the point's x.
            y: the point's y.

        Returns:
            Whether it does.
        """
        return self.rect[0] <= x <= self.rect[2] and self.rect[1] <= y <= self.rect[3]

    def label(self) -> Label:
        """The room's floor label.

        Returns:
            The label.
        """
        return _label(self.instance_id, "floor", self.floor_colour)


@dataclass(frozen=True)
class Doorway:
    """A gap in the wall between two rooms. ``along`` is the axis the wall runs along ('x' or 'y')."""

    rooms: tuple[str, str]
    center: tuple[float, float]
    width: float
    along: str

    def clear_zone(self, depth: float, side_margin: float = 0.1) -> Rect:
        """The rectangle that must stay empty on both sides of the doorway, so the robot can pass.

        Args:
            depth: how far it reaches on each side.
            side_margin: how far past the jambs.

        Returns:
            The rectangle.
        """
        half = self.width / 2 + side_margin
        cx, cy = self.center
        if self.along == "x":
            return (cx - half, cy - depth, cx + half, cy + depth)
        return (cx - depth, cy - half, cx + depth, cy + half)


@dataclass(frozen=True)
class Wall:
    """A wall segment: a box standing on the floor. Walls belong to no single room."""

    instance_id: int
    center: tuple[float, float, float]
    size: tuple[float, float, float]

    @property
    def footprint(self) -> Rect:
        return box_footprint(self.center, self.size)

    def label(self) -> Label:
        """The wall's label.

        Returns:
            The label.
        """
        return _label(self.instance_id, "wall", WALL_COLOUR)


@dataclass(frozen=True)
class Furniture:
    """A furniture piece standing on the floor with its back to a wall.

    ``center`` and ``size`` are the world-aligned box of its body with every part closed (handles
    and open doors stick out of it). ``facing`` is the direction its front faces, in radians: the
    inward normal of the wall behind it, a multiple of pi/2. Storage furniture has its
    ``storage`` model (parts in its local frame, see worlds.storage) and ``joints``, each part's
    joint state by part name; other furniture has None and {}. ``state`` holds visible switches,
    e.g. {"power": "on"} or {"curtain": "closed"}.
    """

    instance_id: int
    category: str
    colour: str
    room: str
    center: tuple[float, float, float]
    size: tuple[float, float, float]
    facing: float = 0.0
    storage: StorageModel | None = None
    joints: dict[str, float] = field(default_factory=dict, hash=False)
    state: dict[str, str] = field(default_factory=dict, hash=False)

    @property
    def footprint(self) -> Rect:
        return box_footprint(self.center, self.size)

    @property
    def top_z(self) -> float:
        return self.center[2] + self.size[2] / 2

    def label(self) -> Label:
        """The piece's label: its id, category and colour.

        Returns:
            The label.
        """
        return _label(self.instance_id, self.category, self.colour)


#: Where a small object is: on a furniture top, inside a storage slot or a container object, under
#: a cover object, or on the floor.
RELATIONS = ("on", "inside", "under", "floor")


@dataclass(frozen=True)
class Item:
    """A small object from the vocabulary, and where it is.

    ``relation`` is one of `RELATIONS`; ``parent`` is the instance id it relates to (a furniture
    piece for 'on' and for 'inside' a storage ``slot``; an object for 'inside' a container, with
    ``slot`` None, and for 'under' a cover), None on the floor. ``center`` is in the world with
    every storage part at its recorded joint state. ``attributes`` holds facts about the object
    itself (e.g. {"upturned": True} for a bowl put over something); ``state`` its switches.
    """

    instance_id: int
    category: str
    colour: str
    room: str
    center: tuple[float, float, float]
    relation: str = "floor"
    parent: int | None = None
    slot: str | None = None
    attributes: dict[str, Any] = field(default_factory=dict, hash=False)
    state: dict[str, str] = field(default_factory=dict, hash=False)

    @property
    def shape(self) -> str:
        return OBJECTS[self.category][0]

    @property
    def dims(self) -> tuple[float, ...]:
        return OBJECTS[self.category][1]

    @property
    def half_extents(self) -> tuple[float, float, float]:
        return half_extents(self.category)

    @property
    def footprint(self) -> Rect:
        hx, hy, _ = self.half_extents
        return (self.center[0] - hx, self.center[1] - hy, self.center[0] + hx, self.center[1] + hy)

    def label(self) -> Label:
        """The object's label: its id, category and colour.

        Returns:
            The label.
        """
        return _label(self.instance_id, self.category, self.colour)


def half_extents(category: str) -> tuple[float, float, float]:
    """Half sizes of the axis-aligned box around an object of ``category``.

    Args:
        category: the object's category.

    Returns:
        The half sizes.
    """
    shape, dims = OBJECTS[category]
    if shape == "box":
        return (dims[0] / 2, dims[1] / 2, dims[2] / 2)
    if shape == "cylinder":
        return (dims[0], dims[0], dims[1] / 2)
    return (dims[0], dims[0], dims[0])
