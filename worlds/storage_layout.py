"""How each storage model is laid out: its front cut into bands and columns of doors, drawers, flaps.

`_assemble` turns a front layout into carcass boards, parts and slots; one small function per model
draws a realistic size and layout from the generator. Frames and conventions: `worlds.storage`.
Every rail and divider stands right behind the gap between two fronts, so no gap lets the camera
see into a closed piece.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from worlds.storage import FRONT, PANEL, PART_KINDS, TRAY_WALL, Box, Part, Slot, StorageModel, Vec3

#: One column of a band: width, kind ("door", "drawer", "flap" or "panel" for a fixed front), hinge, shelves.
Column = tuple[float, str, str | None, int]
#: A horizontal band of the front, bottom up: its height and its columns, left to right.
Band = tuple[float, list[Column]]

_GAP = 0.004  # between neighbouring fronts; a rail or divider always stands behind it
_RUNNER = 0.006  # side clearance between a drawer's tray and the carcass
_CLEAR = 0.01  # free space kept between a slot and the board above it or beside it
_FLAP_UPPER = 1.5


@dataclass(frozen=True)
class _Cell:
    """One column of one band: its front rectangle and the interior behind it (local frame)."""

    front: tuple[float, float, float, float]
    lo: tuple[float, float, float]
    hi: tuple[float, float, float]


def _assemble(model: str, size: Vec3, plinth: float, bands: list[Band], door_upper: float = 1.75) -> StorageModel:
    """Boards, parts and slots from the front's bands; parts are numbered bottom up, left to right."""
    w, d, h = size
    y0, y1 = -d / 2 + FRONT, d / 2 - PANEL  # the interior's depth, behind the fronts, before the back
    panels = [
        Box.between("left", (-w / 2, y0, 0.0), (-w / 2 + PANEL, d / 2, h)),
        Box.between("right", (w / 2 - PANEL, y0, 0.0), (w / 2, d / 2, h)),
        Box.between("back", (-w / 2 + PANEL, y1, 0.0), (w / 2 - PANEL, d / 2, h)),
        Box.between("top", (-w / 2 + PANEL, y0, h - PANEL), (w / 2 - PANEL, y1, h)),
        Box.between("bottom", (-w / 2 + PANEL, y0, plinth), (w / 2 - PANEL, y1, plinth + PANEL)),
    ]
    if plinth > 0:
        panels.append(Box.between("plinth", (-w / 2, -d / 2, 0.0), (w / 2, y0, plinth)))
    parts: list[Part] = []
    slots: list[Slot] = []
    counts = {kind: 0 for kind in PART_KINDS}
    zb0 = plinth
    for b, (height, columns) in enumerate(bands):
        zb1 = zb0 + height
        inner_z = (zb0 + _inset(b == 0), zb1 - _inset(b == len(bands) - 1))
        front_z = (zb0 + _gap(b == 0), zb1 - _gap(b == len(bands) - 1))
        if b > 0:
            rail = ((-w / 2 + PANEL, y0, zb0 - PANEL / 2), (w / 2 - PANEL, y1, zb0 + PANEL / 2))
            panels.append(Box.between(f"rail_{b}", *rail))
        xc0 = -w / 2
        for c, (width, kind, hinge, shelves) in enumerate(columns):
            xc1 = xc0 + width
            first, last = c == 0, c == len(columns) - 1
            cell = _Cell((xc0 + _gap(first), front_z[0], xc1 - _gap(last), front_z[1]),
                         (xc0 + _inset(first), y0, inner_z[0]), (xc1 - _inset(last), y1, inner_z[1]))
            if min(np.subtract(cell.hi, cell.lo)) < 0.04:
                raise ValueError(f"size: {size} leaves no room inside the {model}'s band {b}, column {c}")
            if not first:
                divider = ((xc0 - PANEL / 2, y0, inner_z[0]), (xc0 + PANEL / 2, y1, inner_z[1]))
                panels.append(Box.between(f"divider_{b}_{c}", *divider))
            xc0 = xc1
            if kind == "panel":
                x0, z0, x1, z1 = cell.front
                panels.append(Box.between(f"front_{b}_{c}", (x0, -d / 2, z0), (x1, y0, z1)))
                continue
            name = f"{kind}_{counts[kind]}"
            counts[kind] += 1
            if kind == "drawer":
                parts.append(_drawer(name, cell))
                slots.append(_drawer_slot(parts[-1], cell))
            else:
                upper = door_upper if kind == "door" else _FLAP_UPPER
                parts.append(Part(name, kind, "revolute", 0.0, upper, hinge, f"{name}_handle", cell.front))
                boards, levels = _shelves_behind(name, cell, shelves)
                panels += boards
                slots += levels
        zb0 = zb1
    return StorageModel(model, size, tuple(parts), tuple(slots), tuple(panels))


def _inset(outer: bool) -> float:
    """How far a cell's interior starts from its edge: a whole board at the outside, half a shared one inside."""
    return PANEL if outer else PANEL / 2


def _gap(outer: bool) -> float:
    """How far a front stops short of its cell's edge: flush outside, half the gap to its neighbour inside."""
    return 0.0 if outer else _GAP / 2


def _drawer(name: str, cell: _Cell) -> Part:
    """A drawer filling ``cell``: its front, and a tray that pulls out up to three quarters of its depth."""
    (x0, y0, z0), (x1, y1, z1) = cell.lo, cell.hi
    depth = y1 - y0 - _CLEAR
    tray = Box.between("tray", (x0 + _RUNNER, y0, z0 + 0.004), (x1 - _RUNNER, y0 + depth, z1 - 0.012))
    return Part(name, "drawer", "prismatic", 0.0, round(0.75 * depth, 3), None, f"{name}_handle", cell.front, tray)


def _drawer_slot(drawer: Part, cell: _Cell) -> Slot:
    """The inside of a drawer's tray, up to just under the board above it."""
    assert drawer.tray is not None
    lo, hi = drawer.tray.lo(), drawer.tray.hi()
    wall = TRAY_WALL + _CLEAR / 2
    inside = Box.between(f"{drawer.name}/0", (lo[0] + wall, cell.lo[1] + _CLEAR / 2, lo[2] + TRAY_WALL),
                         (hi[0] - wall, hi[1] - wall, cell.hi[2] - _CLEAR))
    return Slot(inside.name, drawer.name, drawer.name, inside.center, inside.size)


def _shelves_behind(door: str, cell: _Cell, shelves: int) -> tuple[list[Box], list[Slot]]:
    """Evenly spaced shelves in the compartment behind ``door``, and one slot per level."""
    (x0, y0, z0), (x1, y1, z1) = cell.lo, cell.hi
    levels = np.linspace(z0, z1, shelves + 2)
    boards = [Box.between(f"shelf_{door}_{k}", (x0, y0 + 2 * _CLEAR, z - PANEL / 2), (x1, y1, z + PANEL / 2))
              for k, z in enumerate(levels[1:-1].tolist())]
    slots = []
    for k in range(shelves + 1):
        bottom = float(levels[k]) + (PANEL / 2 if k else 0.0)
        top = float(levels[k + 1]) - (PANEL / 2 if k < shelves else 0.0) - _CLEAR
        margin = _CLEAR / 2
        inside = Box.between(f"{door}/{k}", (x0 + margin, y0 + margin, bottom), (x1 - margin, y1 - margin, top))
        slots.append(Slot(inside.name, None, door, inside.center, inside.size))
    return boards, slots


def _size(rng: np.random.Generator, size: Vec3 | None, lo: Vec3, hi: Vec3) -> Vec3:
    if size is None:
        return tuple(round(float(rng.uniform(a, b)), 2) for a, b in zip(lo, hi))  # type: ignore[return-value]
    if len(size) != 3 or not all(isinstance(v, (int, float)) and math.isfinite(v) and v > 0 for v in size):
        raise ValueError(f"size: {size!r} must be three positive metres (width, depth, height)")
    return (float(size[0]), float(size[1]), float(size[2]))


def _hinge(rng: np.random.Generator) -> str:
    return str(rng.choice(("left", "right")))


def _shelves(height: float, spacing: float) -> int:
    """Shelves to put in a compartment of ``height`` so levels are about ``spacing`` apart."""
    return max(0, round(height / spacing) - 1)


def _cabinet(rng: np.random.Generator, size: Vec3 | None) -> StorageModel:
    w, d, h = s = _size(rng, size, (0.5, 0.38, 0.7), (1.0, 0.5, 0.92))
    plinth = 0.05 if h > 0.6 else 0.0
    shelves = min(1, _shelves(h - plinth, 0.3))
    columns: list[Column] = [(w / 2, "door", "left", shelves), (w / 2, "door", "right", shelves)]
    if w < 0.7:
        columns = [(w, "door", _hinge(rng), shelves)]
    return _assemble("cabinet", s, plinth, [(h - plinth, columns)])


def _drawer_chest(rng: np.random.Generator, size: Vec3 | None) -> StorageModel:
    w, d, h = s = _size(rng, size, (0.6, 0.4, 0.7), (1.0, 0.5, 1.1))
    plinth = 0.06 if h > 0.5 else 0.0
    count = max(1, min(int(rng.integers(2, 5)), int((h - plinth) // 0.12)))
    return _assemble("drawer_chest", s, plinth, [((h - plinth) / count, [(w, "drawer", None, 0)])] * count)


def _wardrobe(rng: np.random.Generator, size: Vec3 | None) -> StorageModel:
    w, d, h = s = _size(rng, size, (0.9, 0.55, 1.8), (1.2, 0.62, 2.05))
    shelves = int(rng.integers(2, 4))
    columns: list[Column] = [(w / 2, "door", "left", shelves), (w / 2, "door", "right", shelves)]
    return _assemble("wardrobe", s, 0.08, [(h - 0.08, columns)])


def _nightstand(rng: np.random.Generator, size: Vec3 | None) -> StorageModel:
    w, d, h = s = _size(rng, size, (0.4, 0.35, 0.5), (0.55, 0.45, 0.65))
    plinth = 0.04 if h > 0.4 else 0.0
    drawer = min(round(float(rng.uniform(0.14, 0.18)), 3), 0.45 * (h - plinth))
    bands: list[Band] = [(h - plinth - drawer, [(w, "door", _hinge(rng), 0)]), (drawer, [(w, "drawer", None, 0)])]
    return _assemble("nightstand", s, plinth, bands)


def _fridge(rng: np.random.Generator, size: Vec3 | None) -> StorageModel:
    w, d, h = s = _size(rng, size, (0.55, 0.6, 1.45), (0.75, 0.7, 1.85))
    plinth, hinge = 0.03, _hinge(rng)
    body = h - plinth
    if rng.random() < 0.5:
        return _assemble("fridge", s, plinth, [(body, [(w, "door", hinge, _shelves(body, 0.32))])], 2.0)
    freezer = round(body * float(rng.uniform(0.28, 0.35)), 3)
    bands: list[Band] = [
        (body - freezer, [(w, "door", hinge, _shelves(body - freezer, 0.32))]),
        (freezer, [(w, "door", hinge, _shelves(freezer, 0.32))]),
    ]
    return _assemble("fridge", s, plinth, bands, 2.0)


def _dishwasher(rng: np.random.Generator, size: Vec3 | None) -> StorageModel:
    w, d, h = s = _size(rng, size, (0.6, 0.56, 0.82), (0.6, 0.6, 0.87))
    plinth, panel = (0.1, 0.1) if h > 0.5 else (0.0, 0.05)
    bands: list[Band] = [(h - plinth - panel, [(w, "flap", "bottom", 1)]), (panel, [(w, "panel", None, 0)])]
    return _assemble("dishwasher", s, plinth, bands)


def _counter(rng: np.random.Generator, size: Vec3 | None) -> StorageModel:
    w, d, h = s = _size(rng, size, (1.2, 0.58, 0.88), (2.4, 0.62, 0.92))
    plinth = 0.1 if h > 0.6 else 0.0
    n = int(np.clip(round(w / 0.6), 2, 4))
    drawer = round(float(rng.uniform(0.15, 0.18)), 3)
    doors: list[Column] = [(w / n, "door", "left" if c % 2 == 0 else "right", 1) for c in range(n)]
    drawers: list[Column] = [(w / n, "drawer", None, 0)] * n
    return _assemble("counter", s, plinth, [(h - plinth - drawer, doors), (drawer, drawers)])


LAYOUTS: dict[str, Callable[[np.random.Generator, Vec3 | None], StorageModel]] = {
    "cabinet": _cabinet,
    "drawer_chest": _drawer_chest,
    "wardrobe": _wardrobe,
    "nightstand": _nightstand,
    "fridge": _fridge,
    "dishwasher": _dishwasher,
    "counter": _counter,
}
