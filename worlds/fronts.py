"""Where furniture reaches into its room, in world coordinates.

A storage model (worlds.storage) is described in its own frame with its front facing local -y; in a
home a piece stands at its footprint's centre, turned by quarter turns so its front faces
``facing``. This module answers what the generator asks of such a placement: the zone to keep clear
in front (as deep as doors, drawers and flaps reach when fully open, plus room to stand), what the
parts and handles cover at their recorded joint states (obstacles for the robot), and where a
slot's volume is in the world (where objects inside it stand).
"""

from __future__ import annotations

import math

from worlds.storage import FRONT, HANDLE_REACH, Part, StorageModel, yaw_facing
from worlds.things import Furniture, Rect

Vec3 = tuple[float, float, float]


def to_world(center: tuple[float, ...], facing: float, x: float, y: float) -> tuple[float, float]:
    """A point of a piece's local frame (front facing -y) in the world plane.

    Args:
        center: the piece's centre.
        facing: the way it faces.
        x: the point's local x.
        y: the point's local y.

    Returns:
        The world point.
    """
    yaw = yaw_facing(facing)
    c, s = round(math.cos(yaw)), round(math.sin(yaw))  # quarter turns only: exact
    return (center[0] + c * x - s * y, center[1] + s * x + c * y)


def rect_to_world(center: tuple[float, ...], facing: float, rect: Rect) -> Rect:
    """A rectangle of a piece's local frame (front facing -y) in the world plane.

    Args:
        center: the piece's centre.
        facing: the way it faces.
        rect: the local rectangle.

    Returns:
        The world rectangle.
    """
    (ax, ay), (bx, by) = to_world(center, facing, rect[0], rect[1]), to_world(center, facing, rect[2], rect[3])
    return (min(ax, bx), min(ay, by), max(ax, bx), max(ay, by))


def world_size(size: Vec3, facing: float) -> Vec3:
    """The world-aligned size of a piece of local ``size`` (width, depth, height) facing ``facing``.

    Args:
        size: the local size.
        facing: the way the piece faces.

    Returns:
        The world size.
    """
    across = abs(round(math.cos(yaw_facing(facing)))) == 1
    return size if across else (size[1], size[0], size[2])


def _part_rect(part: Part, depth: float, opening: float, sweep: bool) -> Rect | None:
    """The local rectangle in front of the body that a part (with its handle) covers at ``opening``;
    with ``sweep``, every place it passes through from closed to ``opening``. None while closed."""
    if opening <= 0.0:
        return None
    x0, z0, x1, z1 = part.front
    face, margin = -depth / 2, FRONT + HANDLE_REACH
    if part.kind == "drawer":
        return (x0, face - opening - margin, x1, face)
    width, height = x1 - x0, z1 - z0
    out = math.sin(min(opening, math.pi / 2)) if sweep else math.sin(opening)
    if part.kind == "flap":
        return (x0, face - height * out - margin, x1, face)
    lo, hi = (width * math.cos(opening), width) if sweep else (width * math.cos(opening),) * 2
    reach = (min(lo, 0.0) - margin, max(hi, 0.0) + margin)
    xs = (x0 + reach[0], x0 + reach[1]) if part.hinge == "left" else (x1 - reach[1], x1 - reach[0])
    return (xs[0], face - width * out - margin, xs[1], face)


def _union(rects: list[Rect]) -> Rect:
    return (min(r[0] for r in rects), min(r[1] for r in rects), max(r[2] for r in rects), max(r[3] for r in rects))


def use_zone(center: tuple[float, ...], facing: float, size: Vec3, model: StorageModel | None, stand: float) -> Rect:
    """The world rectangle kept clear in front of a piece: ``stand`` metres deep in front of its face,
    and for storage in front of everything its parts sweep when opened all the way (local ``size``).

    Args:
        center: the piece's centre.
        facing: the way it faces.
        size: its local size.
        model: its storage model, if any.
        stand: the room to stand in front (m).

    Returns:
        The rectangle.
    """
    width, depth = size[0], size[1]
    local = [(-width / 2, -depth / 2 - stand, width / 2, -depth / 2)]
    swept = [] if model is None else [r for p in model.parts if (r := _part_rect(p, depth, p.upper, sweep=True))]
    if swept:
        reach = _union(swept)
        local += [reach, (reach[0], reach[1] - stand, reach[2], reach[1])]
    return rect_to_world(center, facing, _union(local))


def storage_obstacles(piece: Furniture) -> list[Rect]:
    """World rectangles in front of a storage piece's body: its closed handles and its open parts.

    Args:
        piece: the furniture piece.

    Returns:
        The rectangles (none without storage).
    """
    if piece.storage is None:
        return []
    width, depth = piece.storage.size[0], piece.storage.size[1]
    local = [(-width / 2, -depth / 2 - HANDLE_REACH, width / 2, -depth / 2)]
    for part in piece.storage.parts:
        rect = _part_rect(part, depth, piece.joints.get(part.name, 0.0), sweep=False)
        if rect is not None:
            local.append(rect)
    return [rect_to_world(piece.center, piece.facing, rect) for rect in local]


def front_reach(model: StorageModel | None) -> float:
    """How far in front of the body any part of ``model`` reaches when opened all the way, in metres.

    Args:
        model: the storage model, or None.

    Returns:
        The reach (0 without storage).
    """
    if model is None:
        return 0.0
    depth = model.size[1]
    swept = [r for p in model.parts if (r := _part_rect(p, depth, p.upper, sweep=True)) is not None]
    return max((-depth / 2 - r[1] for r in swept), default=0.0)


def stand_point(piece: Furniture, beyond: float) -> tuple[float, float]:
    """The point in front of the middle of ``piece``, ``beyond`` metres past where its parts reach.

    Args:
        piece: the furniture piece.
        beyond: how far past its parts' reach.

    Returns:
        The point.
    """
    depth = piece.storage.size[1] if piece.storage is not None else world_size(piece.size, piece.facing)[1]
    return to_world(piece.center, piece.facing, 0.0, -depth / 2 - front_reach(piece.storage) - beyond)


def slot_box(piece: Furniture, name: str) -> tuple[Vec3, Vec3]:
    """World (centre, size) of slot ``name`` of ``piece``, moved out with its drawer if that is open.

    Args:
        piece: the storage piece.
        name: the slot's name.

    Returns:
        The slot's centre and size.
    """
    assert piece.storage is not None, f"{piece.category} {piece.instance_id} has no storage"
    slot = piece.storage.slot(name)
    pulled = piece.joints.get(slot.part, 0.0) if slot.part is not None else 0.0
    x, y = to_world(piece.center, piece.facing, slot.center[0], slot.center[1] - pulled)
    return (x, y, slot.center[2]), world_size(slot.size, piece.facing)
