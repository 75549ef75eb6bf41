"""Building a HomeSpec into a PyBullet scene: static boxes and primitives, one body per thing.

Every body is static (mass 0) and single-link, so the default segmentation mask gives the body id
per pixel, and the returned table turns body ids into the home's instance labels. Floors are thin
boxes whose top is z = 0, tinted per room so rooms look different from one another.
"""

from __future__ import annotations

import pybullet as p

from worlds.home import HomeSpec
from worlds.things import Item, Label
from worlds.vocabulary import COLOURS

FLOOR_THICKNESS = 0.02
#: Floors and walls are drawn paler than their colour names, the way homes are painted.
_FLOOR_TINT = 0.55
_WALL_RGBA = (0.9, 0.9, 0.88, 1.0)


def _pale(colour: str, amount: float) -> tuple[float, float, float, float]:
    r, g, b, a = COLOURS[colour]
    return (r * amount + (1 - amount), g * amount + (1 - amount), b * amount + (1 - amount), a)


def _box(client: int, center: tuple[float, ...], size: tuple[float, ...], rgba: tuple[float, ...]) -> int:
    half = [s / 2 for s in size]
    collision = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=client)
    visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=client)
    return p.createMultiBody(0.0, collision, visual, list(center), physicsClientId=client)


def _item(client: int, item: Item) -> int:
    rgba = COLOURS[item.colour]
    dims = item.dims
    if item.shape == "box":
        return _box(client, item.center, dims, rgba)
    if item.shape == "cylinder":
        shape = {"radius": dims[0]}
        collision = p.createCollisionShape(p.GEOM_CYLINDER, height=dims[1], physicsClientId=client, **shape)
        visual = p.createVisualShape(p.GEOM_CYLINDER, length=dims[1], rgbaColor=rgba, physicsClientId=client, **shape)
    else:
        collision = p.createCollisionShape(p.GEOM_SPHERE, radius=dims[0], physicsClientId=client)
        visual = p.createVisualShape(p.GEOM_SPHERE, radius=dims[0], rgbaColor=rgba, physicsClientId=client)
    return p.createMultiBody(0.0, collision, visual, list(item.center), physicsClientId=client)


def build_scene(home: HomeSpec, client: int) -> dict[int, Label]:
    """Add ``home`` to the (empty) simulation ``client``; return body id -> label for every body."""
    labels: dict[int, Label] = {}
    for room in home.rooms:
        x0, y0, x1, y1 = room.rect
        center = ((x0 + x1) / 2, (y0 + y1) / 2, -FLOOR_THICKNESS / 2)
        body = _box(client, center, (x1 - x0, y1 - y0, FLOOR_THICKNESS), _pale(room.floor_colour, _FLOOR_TINT))
        labels[body] = room.label()
    for wall in home.walls:
        labels[_box(client, wall.center, wall.size, _WALL_RGBA)] = wall.label()
    for piece in home.furniture:
        labels[_box(client, piece.center, piece.size, COLOURS[piece.colour])] = piece.label()
    for item in home.objects:
        labels[_item(client, item)] = item.label()
    return labels


def floor_bodies(labels: dict[int, Label]) -> set[int]:
    """The bodies the robot stands on, which never count as collisions."""
    return {body for body, label in labels.items() if label["category"] == "floor"}
