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
``yaw = theta + pi/2`` (`yaw_facing`). Pieces placed in a scene, with their part ids and labels,
are `worlds.storage_placement`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

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


def yaw_facing(theta: float) -> float:
    """The yaw that turns a piece's front (local -y) towards the world direction ``theta``.

    Args:
        theta: the direction the front faces (rad).

    Returns:
        The yaw, in (-π, π].
    """
    yaw = theta + math.pi / 2
    return math.atan2(math.sin(yaw), math.cos(yaw))
