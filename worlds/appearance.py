"""How a thing looks, from its category, colour and switches: the shapes a renderer draws for it.

Questions about state ("Is the TV in the living room on or off?") are answered by looking, so a
switch must change the picture: a lamp's shade glows when it is on, a TV's screen is lit or black,
a stove's burners glow red, a curtain is drawn across its window or bunched at its sides. This is
a pure mapping from a `Furniture` piece or an `Item` to `Visual` primitives in world coordinates;
worlds.scene turns them into one body per thing (one label), and worlds.scene_cli draws the
same states from above. Storage furniture is not drawn here: its parts come from worlds.urdf.
"""

from __future__ import annotations

from dataclasses import dataclass

from worlds.fronts import to_world, world_size
from worlds.things import Furniture, Item
from worlds.vocabulary import COLOURS

RGBA = tuple[float, float, float, float]

LIT_SHADE: RGBA = (1.0, 0.96, 0.72, 1.0)
LIT_SCREEN: RGBA = (0.55, 0.8, 1.0, 1.0)
DARK_SCREEN: RGBA = (0.02, 0.02, 0.03, 1.0)
HOT_BURNER: RGBA = (1.0, 0.18, 0.05, 1.0)
COLD_BURNER: RGBA = (0.22, 0.22, 0.22, 1.0)
WINDOW: RGBA = (0.72, 0.86, 1.0, 1.0)
METAL: RGBA = (0.3, 0.3, 0.32, 1.0)
#: Share of a curtain's width each bunched-up half keeps when the curtain is open.
OPEN_CURTAIN_SHARE = 0.18


@dataclass(frozen=True)
class Visual:
    """One primitive: a box (``dims`` = full size x, y, z), an upright cylinder (radius, length) or
    a sphere (radius,), centred at ``center`` in the world."""

    shape: str
    center: tuple[float, float, float]
    dims: tuple[float, ...]
    rgba: RGBA


def _dim(colour: str, amount: float) -> RGBA:
    r, g, b, a = COLOURS[colour]
    return (r * amount, g * amount, b * amount, a)


def is_on(state: dict[str, str]) -> bool:
    """Whether a thing's state says it is switched on.

    Args:
        state: the thing's state (``power`` "on" or "off", if it has one).

    Returns:
        Whether it is on.
    """
    return state.get("power") == "on"


def furniture_visuals(piece: Furniture) -> tuple[Visual, ...]:
    """What to draw for a furniture piece without storage: one box, or its parts if it has switches.

    Args:
        piece: the furniture piece.

    Returns:
        The visuals.
    """
    draw = _DRAWERS.get(piece.category)
    if draw is None:
        return (Visual("box", piece.center, piece.size, COLOURS[piece.colour]),)
    return draw(piece)


def item_visuals(item: Item) -> tuple[Visual, ...]:
    """What to draw for a small object: its primitive, or a base, stem and shade for a table lamp.

    Args:
        item: the object.

    Returns:
        The visuals.
    """
    if item.category != "table lamp":
        return (Visual(item.shape, item.center, item.dims, COLOURS[item.colour]),)
    x, y, z = item.center
    radius, height = item.dims
    bottom = z - height / 2
    shade = LIT_SHADE if is_on(item.state) else _dim(item.colour, 0.75)
    return (
        Visual("cylinder", (x, y, bottom + 0.015), (0.6 * radius, 0.03), METAL),
        Visual("cylinder", (x, y, bottom + 0.03 + 0.25 * height), (0.1 * radius, 0.5 * height), METAL),
        Visual("cylinder", (x, y, bottom + 0.775 * height), (radius, 0.45 * height), shade),
    )


def _local(piece: Furniture, x: float, y: float, z: float) -> tuple[float, float, float]:
    """A point of the piece's own frame (x along its wall, front towards -y, z up) in the world."""
    wx, wy = to_world(piece.center, piece.facing, x, y)
    return (wx, wy, z)


def _box(piece: Furniture, x: float, y: float, z: float, size: tuple[float, float, float], rgba: RGBA) -> Visual:
    return Visual("box", _local(piece, x, y, z), world_size(size, piece.facing), rgba)


def _floor_lamp(piece: Furniture) -> tuple[Visual, ...]:
    x, y, _ = piece.center
    height = piece.size[2]
    radius = min(piece.size[0], piece.size[1]) / 2
    shade = LIT_SHADE if is_on(piece.state) else _dim(piece.colour, 0.75)
    return (
        Visual("cylinder", (x, y, 0.015), (0.7 * radius, 0.03), METAL),
        Visual("cylinder", (x, y, 0.03 + 0.39 * height), (0.04 * radius, 0.78 * height), METAL),
        Visual("cylinder", (x, y, 0.9 * height), (radius, 0.2 * height), shade),
    )


def _tv(piece: Furniture) -> tuple[Visual, ...]:
    width, depth, height = world_size(piece.size, piece.facing)
    stand = 0.45
    screen = height - stand - 0.05
    face = -depth / 2 + 0.1
    lit = LIT_SCREEN if is_on(piece.state) else DARK_SCREEN
    return (
        _box(piece, 0.0, 0.0, stand / 2, (width, depth, stand), COLOURS[piece.colour]),
        _box(piece, 0.0, 0.06, stand + 0.025, (0.3 * width, 0.12, 0.05), METAL),
        _box(piece, 0.0, face + 0.04, stand + 0.05 + screen / 2, (width, 0.05, screen), DARK_SCREEN),
        _box(piece, 0.0, face + 0.01, stand + 0.05 + screen / 2, (width - 0.06, 0.01, screen - 0.06), lit),
    )


def _stove(piece: Furniture) -> tuple[Visual, ...]:
    width, depth, height = world_size(piece.size, piece.facing)
    burner = HOT_BURNER if is_on(piece.state) else COLD_BURNER
    top = height - 0.01
    parts = [
        _box(piece, 0.0, 0.0, top / 2, (width, depth, top), COLOURS[piece.colour]),
        _box(piece, 0.0, 0.0, top + 0.005, (width - 0.04, depth - 0.04, 0.01), DARK_SCREEN),
    ]
    for bx in (-width / 4, width / 4):
        for by in (-depth / 4, depth / 4):
            parts.append(Visual("cylinder", _local(piece, bx, by, height + 0.004), (0.07, 0.008), burner))
    return tuple(parts)


def _curtain(piece: Furniture) -> tuple[Visual, ...]:
    """A window on the wall behind, a rod, and the curtain across it (closed) or at its sides (open)."""
    width, depth, height = world_size(piece.size, piece.facing)
    back, front = depth / 2, -depth / 2
    cloth = COLOURS[piece.colour]
    parts = [
        _box(piece, 0.0, back - 0.005, 1.5, (width - 0.1, 0.01, 1.2), WINDOW),
        _box(piece, 0.0, 0.0, height - 0.02, (width, 0.02, 0.02), METAL),
    ]
    hang = height - 0.08
    if piece.state.get("curtain") == "closed":
        parts.append(_box(piece, 0.0, front + 0.015, 0.05 + hang / 2, (width, 0.03, hang), cloth))
    else:
        side = OPEN_CURTAIN_SHARE * width
        for x in (-width / 2 + side / 2, width / 2 - side / 2):
            parts.append(_box(piece, x, front + 0.02, 0.05 + hang / 2, (side, 0.04, hang), cloth))
    return tuple(parts)


_DRAWERS = {"lamp": _floor_lamp, "tv": _tv, "stove": _stove, "curtain": _curtain}
