"""The things a home is made of, as plain frozen data with JSON-able dicts and ground-truth labels.

Everything is an axis-aligned box (or a primitive inside one) on a flat floor at z = 0, so every
question about free space reduces to rectangles in the plane: a `Rect` is ``(xmin, ymin, xmax, ymax)``
in metres. Every rendered thing has a stable ``instance_id`` and a label
``{"id", "category", "colour", "room"}``: the same label the camera reports for its pixels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any, TypeVar

from worlds.vocabulary import OBJECTS

Rect = tuple[float, float, float, float]
Label = dict[str, Any]
T = TypeVar("T")

WALL_COLOUR = "white"


def rect_gap(a: Rect, b: Rect) -> float:
    """Euclidean distance between two rectangles; 0 when they touch or overlap."""
    dx = max(a[0] - b[2], b[0] - a[2], 0.0)
    dy = max(a[1] - b[3], b[1] - a[3], 0.0)
    return math.hypot(dx, dy)


def rects_overlap(a: Rect, b: Rect) -> bool:
    """Whether two rectangles share interior area (touching edges do not count)."""
    return a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]


def point_rect_distance(x: float, y: float, rect: Rect) -> float:
    """Distance from a point to a rectangle; 0 inside it."""
    return rect_gap((x, y, x, y), rect)


def shrink(rect: Rect, margin: float) -> Rect:
    return (rect[0] + margin, rect[1] + margin, rect[2] - margin, rect[3] - margin)


def box_footprint(center: tuple[float, ...], size: tuple[float, ...]) -> Rect:
    return (center[0] - size[0] / 2, center[1] - size[1] / 2, center[0] + size[0] / 2, center[1] + size[1] / 2)


def _label(instance_id: int, category: str, colour: str, room: str) -> Label:
    return {"id": instance_id, "category": category, "colour": colour, "room": room}


def to_plain(thing: Any) -> dict[str, Any]:
    """A dataclass as a JSON-able dict (tuples become lists)."""
    return {f.name: list(v) if isinstance(v := getattr(thing, f.name), tuple) else v for f in fields(thing)}


def from_plain(cls: type[T], data: dict[str, Any]) -> T:
    """The inverse of `to_plain`: lists become tuples again, so a round trip compares equal."""
    names = {f.name for f in fields(cls)}  # type: ignore[arg-type]
    unknown = set(data) - names
    if unknown:
        raise ValueError(f"{cls.__name__}: unknown fields {sorted(unknown)}")
    return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in data.items()})


@dataclass(frozen=True)
class Room:
    """A rectangular room; its floor is a thing of its own (category 'floor') with the room's id."""

    instance_id: int
    name: str
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
        return self.rect[0] <= x <= self.rect[2] and self.rect[1] <= y <= self.rect[3]

    def label(self) -> Label:
        return _label(self.instance_id, "floor", self.floor_colour, self.name)


@dataclass(frozen=True)
class Doorway:
    """A gap in the wall between two rooms. ``along`` is the axis the wall runs along ('x' or 'y')."""

    rooms: tuple[str, str]
    center: tuple[float, float]
    width: float
    along: str

    def clear_zone(self, depth: float, side_margin: float = 0.1) -> Rect:
        """The rectangle that must stay empty on both sides of the doorway, so the robot can pass."""
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
        return _label(self.instance_id, "wall", WALL_COLOUR, "")


@dataclass(frozen=True)
class Furniture:
    """A static furniture box standing on the floor; small objects may rest on its top."""

    instance_id: int
    category: str
    colour: str
    room: str
    center: tuple[float, float, float]
    size: tuple[float, float, float]

    @property
    def footprint(self) -> Rect:
        return box_footprint(self.center, self.size)

    @property
    def top_z(self) -> float:
        return self.center[2] + self.size[2] / 2

    def label(self) -> Label:
        return _label(self.instance_id, self.category, self.colour, self.room)


@dataclass(frozen=True)
class Item:
    """A small object from the vocabulary, on the floor (``on`` is None) or on a furniture top."""

    instance_id: int
    category: str
    colour: str
    room: str
    center: tuple[float, float, float]
    on: int | None

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
        return _label(self.instance_id, self.category, self.colour, self.room)


def half_extents(category: str) -> tuple[float, float, float]:
    """Half sizes of the axis-aligned box around an object of ``category``."""
    shape, dims = OBJECTS[category]
    if shape == "box":
        return (dims[0] / 2, dims[1] / 2, dims[2] / 2)
    if shape == "cylinder":
        return (dims[0], dims[0], dims[1] / 2)
    return (dims[0], dims[0], dims[0])
