"""Articulated storage furniture as plain data: carcass boards, doors, drawers, flaps, handles, slots.

RoboEXP explores by opening things, so storage is not a box: each door, drawer and flap is its own
link on its own joint, each with a handle link of its own (a vertical bar on doors, a horizontal bar
on drawers and flaps, the cue the paper uses to tell a drawer from a door).

Conventions (the local frame of one piece):
- origin at the centre of the footprint on the surface it stands on; x across the width, y through
  the depth, z up; ``size`` is (width x, depth y, height z) without the handles;
- the FRONT faces local -y. Someone standing in front looks along +y, so "left" is -x;
  a door hinged "left" turns about a vertical axis at its -x edge. Fronts fill
  y in [-depth/2, -depth/2 + FRONT]; handles stand `HANDLE_REACH` further out, in front of -depth/2;
- every joint is closed at 0 and opens with positive values (radians or metres) up to ``upper``;
- a `Slot` is a free volume where a small object may stand, given in the local frame with every
  part closed; its bottom face is the surface that carries the object. A slot with ``part`` set lies
  in that drawer and moves with it (by -y times the drawer's opening); ``access`` names the part
  that hides the slot: opening it reveals and reaches the slot.
To put a piece against a wall whose inward normal points at angle ``theta``, use
``yaw = theta + pi/2`` (`yaw_facing`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # homes are made of storage, so only the type is needed here
    from worlds.home import HomeSpec

Vec3 = tuple[float, float, float]

MODELS = ("cabinet", "drawer_chest", "wardrobe", "nightstand", "fridge", "dishwasher", "counter")
PART_KINDS = ("door", "drawer", "flap")

PANEL = 0.018  # carcass board thickness
FRONT = 0.02  # door, flap and drawer-front thickness
HANDLE_OUT = 0.035  # from the front face to the handle bar's centre line
HANDLE_BAR = 0.016  # the bar's square cross-section
HANDLE_REACH = HANDLE_OUT + HANDLE_BAR / 2  # how far handles stick out in front of the size
TRAY_WALL = 0.012  # a drawer tray's bottom, sides and back


@dataclass(frozen=True)
class Box:
    """An axis-aligned box: one board, one drawer wall, one handle bar."""

    name: str
    center: Vec3
    size: Vec3

    @classmethod
    def between(cls, name: str, lo: tuple[float, ...] | np.ndarray, hi: tuple[float, ...] | np.ndarray) -> Box:
        """The box between two opposite corners.

        Args:
            name: the box's name.
            lo: one corner.
            hi: the opposite corner.

        Returns:
            The box.
        """
        center = tuple(float(a + b) / 2 for a, b in zip(lo, hi))
        return cls(name, center, tuple(float(b - a) for a, b in zip(lo, hi)))  # type: ignore[arg-type]

    def lo(self) -> np.ndarray:
        """The box's lowest corner.

        Returns:
            The corner (3,).
        """
        return np.asarray(self.center) - np.asarray(self.size) / 2

    def hi(self) -> np.ndarray:
        """The box's highest corner.

        Returns:
            The corner (3,).
        """
        return np.asarray(self.center) + np.asarray(self.size) / 2

    def contains(self, other: Box, tol: float = 1e-9) -> bool:
        """Whether ``other`` lies wholly inside this box, give or take ``tol``.

        Args:
            other: the other box.
            tol: the tolerance (m).

        Returns:
            Whether it does.
        """
        return bool(np.all(other.lo() >= self.lo() - tol) and np.all(other.hi() <= self.hi() + tol))


@dataclass(frozen=True)
class Part:
    """A door, drawer or flap: one moving link on one joint, with its handle link.

    ``front`` is the front panel's rectangle (xmin, zmin, xmax, zmax) in the local frame; ``tray`` is
    a drawer's box (the front excluded) in the local frame, closed; None for doors and flaps.
    ``hinge`` is "left" or "right" for doors, "bottom" for flaps, None for drawers. In the URDF the
    part is link ``name`` on joint ``<name>_joint``; its handle is link ``handle`` (``<name>_handle``).
    """

    name: str
    kind: str
    joint: str
    lower: float
    upper: float
    hinge: str | None
    handle: str
    front: tuple[float, float, float, float]
    tray: Box | None = None


@dataclass(frozen=True)
class Slot:
    """A free volume for small objects (local frame, every part closed; bottom face carries them)."""

    name: str
    part: str | None
    access: str
    center: Vec3
    size: Vec3

    def box(self) -> Box:
        """The slot's space as a box of the same name.

        Returns:
            The box.
        """
        return Box(self.name, self.center, self.size)


@dataclass(frozen=True)
class StorageModel:
    """One piece of storage furniture: carcass boards (the base link), parts and slots."""

    model: str
    size: Vec3
    parts: tuple[Part, ...]
    slots: tuple[Slot, ...]
    panels: tuple[Box, ...]

    def part(self, name: str) -> Part:
        """The part called ``name``.

        Args:
            name: the part's name.

        Returns:
            The part.

        Raises:
            KeyError: no such part, naming those there are.
        """
        for part in self.parts:
            if part.name == name:
                return part
        raise KeyError(f"{self.model}: no part {name!r}; parts are {[p.name for p in self.parts]}")

    def slot(self, name: str) -> Slot:
        """The slot called ``name``.

        Args:
            name: the slot's name.

        Returns:
            The slot.

        Raises:
            KeyError: no such slot, naming those there are.
        """
        for slot in self.slots:
            if slot.name == name:
                return slot
        raise KeyError(f"{self.model}: no slot {name!r}; slots are {[s.name for s in self.slots]}")

    def to_dict(self) -> dict[str, Any]:
        """The model as plain data, for scene specs.

        Returns:
            The dict.
        """
        return {
            "model": self.model,
            "size": list(self.size),
            "parts": [_part_dict(p) for p in self.parts],
            "slots": [_plain(s) for s in self.slots],
            "panels": [_plain(b) for b in self.panels],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> StorageModel:
        """A model read back from its `to_dict` form.

        Args:
            data: the dict.

        Returns:
            The model.
        """
        parts = tuple(
            Part(**{**p, "front": tuple(p["front"]), "tray": None if p["tray"] is None else _box(p["tray"])})
            for p in data["parts"]
        )
        slots = tuple(Slot(**{**s, "center": tuple(s["center"]), "size": tuple(s["size"])}) for s in data["slots"])
        return cls(data["model"], tuple(data["size"]), parts, slots, tuple(_box(b) for b in data["panels"]))


def _plain(thing: Any) -> dict[str, Any]:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in vars(thing).items()}


def _box(data: dict[str, Any]) -> Box:
    return Box(data["name"], tuple(data["center"]), tuple(data["size"]))


def _part_dict(part: Part) -> dict[str, Any]:
    return {**_plain(part), "tray": None if part.tray is None else _plain(part.tray)}


def storage_model(model: str, rng: np.random.Generator, size: Vec3 | None = None) -> StorageModel:
    """A ``model`` piece with realistic proportions; ``size`` overrides the drawn outer size.

    Args:
        model: the model's name (one of `MODELS`).
        rng: the proportions' generator.
        size: the outer size, or None to draw it.

    Returns:
        The model.

    Raises:
        ValueError: an unknown model.
    """
    if model not in MODELS:
        raise ValueError(f"model: {model!r} is not one of {MODELS}")
    from worlds.storage_layout import LAYOUTS  # the layouts build the classes defined here

    return LAYOUTS[model](rng, size)


@dataclass(frozen=True)
class StoragePlacement:
    """One storage piece placed in a scene: where, how open, and which small objects are in which slot.

    ``pose`` is (x, y, z, yaw) of the local origin: z is the top of what it stands on (0 on the
    floor). Instance ids: the carcass keeps ``furniture_id``; part k (in ``model.parts`` order) gets
    ``first_part_id + 2k`` and its handle ``first_part_id + 2k + 1``. ``contents`` pairs an object's
    instance id with the slot it stands in; the object's own centre is where it stands.
    """

    furniture_id: int
    model: StorageModel
    pose: tuple[float, float, float, float]
    first_part_id: int
    states: tuple[tuple[str, float], ...] = ()
    contents: tuple[tuple[int, str], ...] = ()

    def part_ids(self) -> dict[str, int]:
        """Link name (part or handle) -> instance id.

        Returns:
            The ids.
        """
        ids: dict[str, int] = {}
        for k, part in enumerate(self.model.parts):
            ids[part.name], ids[part.handle] = self.first_part_id + 2 * k, self.first_part_id + 2 * k + 1
        return ids

    def state(self, part: str) -> float:
        """A part's joint value in this placement (0, closed, when not given).

        Args:
            part: the part's name.

        Returns:
            The value (rad or m).
        """
        return dict(self.states).get(part, 0.0)

    def slot_spot(self, slot: str, half_height: float, dx: float = 0.0, dy: float = 0.0) -> np.ndarray:
        """World centre of an object ``half_height`` tall standing in ``slot`` at (dx, dy) from its middle.

        A slot in a drawer is taken where the drawer stands in ``states``.

        Args:
            slot: the slot's name.
            half_height: half the object's height.
            dx: the offset across the slot.
            dy: the offset into the slot.

        Returns:
            The centre (3,).
        """
        box = self.model.slot(slot)
        pulled = self.state(box.part) if box.part is not None else 0.0
        cx, cy, cz = box.center
        return self.to_world((cx + dx, cy + dy - pulled, cz - box.size[2] / 2 + half_height))

    def footprint(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) in the world around the closed piece and its handles.

        Returns:
            The footprint.
        """
        w, d, _ = self.model.size
        corners = [self.to_world((sx * w / 2, y, 0.0)) for sx in (-1, 1) for y in (-d / 2 - HANDLE_REACH, d / 2)]
        xs, ys = [c[0] for c in corners], [c[1] for c in corners]
        return (min(xs), min(ys), max(xs), max(ys))

    def to_world(self, local: tuple[float, ...] | np.ndarray) -> np.ndarray:
        """Points of the local frame, shape (3,) or (N, 3), in the world.

        Args:
            local: the points.

        Returns:
            The world points, shaped the same.
        """
        x, y, z, yaw = self.pose
        c, s = math.cos(yaw), math.sin(yaw)
        rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return np.asarray(local, dtype=float) @ rotation.T + np.array([x, y, z])

    def to_dict(self) -> dict[str, Any]:
        """The placement as plain data, for scene specs.

        Returns:
            The dict.
        """
        return {
            "furniture_id": self.furniture_id,
            "model": self.model.to_dict(),
            "pose": list(self.pose),
            "first_part_id": self.first_part_id,
            "states": [list(s) for s in self.states],
            "contents": [list(c) for c in self.contents],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> StoragePlacement:
        """A placement read back from its `to_dict` form.

        Args:
            data: the dict.

        Returns:
            The placement.
        """
        return cls(
            int(data["furniture_id"]),
            StorageModel.from_dict(data["model"]),
            tuple(data["pose"]),
            int(data["first_part_id"]),
            tuple((str(n), float(v)) for n, v in data["states"]),
            tuple((int(i), str(s)) for i, s in data["contents"]),
        )


def part_labels(placement: StoragePlacement, colour: str) -> dict[str, dict[str, Any]]:
    """Link name -> ground-truth label for every part ("door" or "drawer"; flaps are doors) and handle.

    Args:
        placement: the placed piece.
        colour: the piece's colour.

    Returns:
        The labels.
    """
    ids = placement.part_ids()
    labels: dict[str, dict[str, Any]] = {}
    for part in placement.model.parts:
        category = "drawer" if part.kind == "drawer" else "door"
        labels[part.name] = {"id": ids[part.name], "category": category, "colour": colour}
        handle = {"id": ids[part.handle], "category": "handle", "colour": handle_colour(colour)}
        labels[part.handle] = handle
    return labels


def home_storage(home: HomeSpec) -> list[StoragePlacement]:
    """Every storage piece of ``home`` as a placement; parts and handles get ids after every other thing.

    Ids are handed out in furniture order, two per part (the part, then its handle), starting right
    after the largest instance id in the home, so the same home always labels its parts the same.

    Args:
        home: the home.

    Returns:
        The placements, in furniture order.
    """
    things = (*home.rooms, *home.walls, *home.furniture, *home.objects)
    next_id = max((thing.instance_id for thing in things), default=0) + 1
    placements = []
    for piece in home.furniture:
        if piece.storage is None:
            continue
        contents = tuple(
            (item.instance_id, item.slot)
            for item in home.objects
            if item.parent == piece.instance_id and item.relation == "inside" and item.slot is not None
        )
        pose = (piece.center[0], piece.center[1], piece.center[2] - piece.size[2] / 2, yaw_facing(piece.facing))
        states = tuple(sorted(piece.joints.items()))
        placements.append(StoragePlacement(piece.instance_id, piece.storage, pose, next_id, states, contents))
        next_id += 2 * len(piece.storage.parts)
    return placements


def home_part_labels(home: HomeSpec) -> dict[int, dict[str, Any]]:
    """Instance id -> label of every storage part and handle in ``home`` (the ids `home_storage` hands out).

    Args:
        home: the home.

    Returns:
        The labels by id.
    """
    colours = {piece.instance_id: piece.colour for piece in home.furniture}
    return {
        label["id"]: label
        for placement in home_storage(home)
        for label in part_labels(placement, colours[placement.furniture_id]).values()
    }


def handle_colour(colour: str) -> str:
    """Handles are black, except on black furniture where they are white: they must stand out.

    Args:
        colour: the furniture's colour.

    Returns:
        The handles' colour.
    """
    return "white" if colour == "black" else "black"


def yaw_facing(theta: float) -> float:
    """The yaw that turns a piece's front (local -y) towards the world direction ``theta``.

    Args:
        theta: the direction the front faces (rad).

    Returns:
        The yaw, in (-π, π].
    """
    yaw = theta + math.pi / 2
    return math.atan2(math.sin(yaw), math.cos(yaw))
