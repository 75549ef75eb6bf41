"""Building a HomeSpec into a PyBullet scene, and loading articulated storage furniture.

Plain things are static (mass 0) single-link bodies. Storage pieces are fixed-base multi-link
bodies loaded from generated URDF, each door, drawer and handle a link of its own. Segmentation is
read per body and link (`ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX`), so labels are keyed by
``(body, link)``: ``(body, -1)`` labels every link of a body that has no label of its own, which is
how single-link things and storage carcasses are labelled, while each part and handle gets its own.
Floors are thin boxes whose top is z = 0, tinted per room so rooms look different from one another.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import pybullet as p

from worlds.appearance import Visual, furniture_visuals, item_visuals
from worlds.camera import SegLabels
from worlds.storage import StorageModel
from worlds.storage_placement import StoragePlacement, handle_colour, home_storage, part_labels
from worlds.things import Item, Label
from worlds.urdf import HANDLE_RGBA, friction, storage_urdf
from worlds.vocabulary import COLOURS

if TYPE_CHECKING:  # only its shape is used here; scene loading must not pull in the generator
    from worlds.home import HomeSpec

FLOOR_THICKNESS = 0.02
#: Floors and walls are drawn paler than their colour names, the way homes are painted.
_FLOOR_TINT = 0.55
_WALL_RGBA = (0.9, 0.9, 0.88, 1.0)
#: Where generated URDF files are cached, one per distinct text.
URDF_CACHE = Path(tempfile.gettempdir()) / "homebot-urdf"


@dataclass
class StorageBody:
    """A loaded storage piece: its body, its placement and its link indices by link name."""

    body: int
    placement: StoragePlacement
    links: dict[str, int]


@dataclass
class BuiltScene:
    """What a build added: every label, the bodies of small objects, and the storage pieces."""

    labels: SegLabels = field(default_factory=dict)
    items: dict[int, int] = field(default_factory=dict)  # object instance id -> body
    storage: dict[int, StorageBody] = field(default_factory=dict)  # furniture instance id -> piece


def _pale(colour: str, amount: float) -> tuple[float, float, float, float]:
    r, g, b, a = COLOURS[colour]
    return (r * amount + (1 - amount), g * amount + (1 - amount), b * amount + (1 - amount), a)


def add_box(client: int, center: Sequence[float], size: Sequence[float], rgba: Sequence[float]) -> int:
    """A static box body.

    Args:
        client: the PyBullet client.
        center: the box's centre.
        size: its size.
        rgba: its colour.

    Returns:
        The body id.
    """
    half = [s / 2 for s in size]
    collision = p.createCollisionShape(p.GEOM_BOX, halfExtents=half, physicsClientId=client)
    visual = p.createVisualShape(p.GEOM_BOX, halfExtents=half, rgbaColor=rgba, physicsClientId=client)
    return p.createMultiBody(0.0, collision, visual, list(center), physicsClientId=client)


def add_boxes(client: int, origin: Sequence[float], boxes: Sequence[tuple[Sequence[float], Sequence[float]]],
              rgba: Sequence[float]) -> int:
    """A static single-link body made of several boxes, each (centre relative to ``origin``, size).

    Args:
        client: the PyBullet client.
        origin: the body's origin.
        boxes: the boxes.
        rgba: their colour.

    Returns:
        The body id.
    """
    halves = [[s / 2 for s in size] for _, size in boxes]
    centres = [list(centre) for centre, _ in boxes]
    kinds = [p.GEOM_BOX] * len(boxes)
    collision = p.createCollisionShapeArray(kinds, halfExtents=halves, collisionFramePositions=centres,
                                            physicsClientId=client)
    visual = p.createVisualShapeArray(kinds, halfExtents=halves, visualFramePositions=centres,
                                      rgbaColors=[list(rgba)] * len(boxes), physicsClientId=client)
    return p.createMultiBody(0.0, collision, visual, list(origin), physicsClientId=client)


def add_shape(client: int, shape: str, dims: Sequence[float], center: Sequence[float], rgba: Sequence[float]) -> int:
    """A static body: a box (x, y, z), an upright cylinder (radius, height) or a sphere (radius).

    Args:
        client: the PyBullet client.
        shape: "box", "cylinder", or anything else for a sphere.
        dims: its dimensions.
        center: its centre.
        rgba: its colour.

    Returns:
        The body id.
    """
    if shape == "box":
        return add_box(client, center, dims, rgba)
    if shape == "cylinder":
        radius, height = dims
        collision = p.createCollisionShape(p.GEOM_CYLINDER, radius=radius, height=height, physicsClientId=client)
        visual = p.createVisualShape(p.GEOM_CYLINDER, radius=radius, length=height, rgbaColor=rgba,
                                     physicsClientId=client)
    else:
        collision = p.createCollisionShape(p.GEOM_SPHERE, radius=dims[0], physicsClientId=client)
        visual = p.createVisualShape(p.GEOM_SPHERE, radius=dims[0], rgbaColor=rgba, physicsClientId=client)
    return p.createMultiBody(0.0, collision, visual, list(center), physicsClientId=client)


def add_item(client: int, item: Item) -> int:
    """A static body for a small object of the home.

    Args:
        client: the PyBullet client.
        item: the object.

    Returns:
        The body id.
    """
    return add_shape(client, item.shape, item.dims, item.center, COLOURS[item.colour])


def add_visuals(client: int, center: Sequence[float], size: Sequence[float], visuals: Sequence[Visual]) -> int:
    """A static body that collides as one box of ``size`` and looks like ``visuals`` (worlds.appearance:
    a lamp's glowing shade, a TV's lit screen), one body so the whole thing carries one label.

    Args:
        client: the PyBullet client.
        center: the body's centre.
        size: its collision box's size.
        visuals: what it looks like.

    Returns:
        The body id.
    """
    kinds = {"box": p.GEOM_BOX, "cylinder": p.GEOM_CYLINDER, "sphere": p.GEOM_SPHERE}
    collision = p.createCollisionShape(p.GEOM_BOX, halfExtents=[s / 2 for s in size], physicsClientId=client)
    visual = p.createVisualShapeArray(
        [kinds[v.shape] for v in visuals],
        halfExtents=[[d / 2 for d in v.dims] if v.shape == "box" else [0.0] * 3 for v in visuals],
        radii=[v.dims[0] if v.shape != "box" else 0.0 for v in visuals],
        lengths=[v.dims[1] if v.shape == "cylinder" else 0.0 for v in visuals],
        rgbaColors=[list(v.rgba) for v in visuals],
        visualFramePositions=[[a - b for a, b in zip(v.center, center)] for v in visuals],
        physicsClientId=client,
    )
    return p.createMultiBody(0.0, collision, visual, list(center), physicsClientId=client)


def urdf_file(text: str) -> Path:
    """The cached file holding ``text``, written once per content (atomically, so parallel runs agree).

    Args:
        text: the URDF.

    Returns:
        The file's path.
    """
    path = URDF_CACHE / f"{hashlib.sha256(text.encode()).hexdigest()[:20]}.urdf"
    if not path.exists():
        URDF_CACHE.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=URDF_CACHE, suffix=".tmp")
        with os.fdopen(fd, "w") as handle:
            handle.write(text)
        os.replace(tmp, path)
    return path


def link_indices(client: int, body: int) -> dict[str, int]:
    """Link name -> link index (the index of the joint whose child it is).

    Args:
        client: the PyBullet client.
        body: the body.

    Returns:
        The indices by link name.
    """
    return {
        p.getJointInfo(body, j, physicsClientId=client)[12].decode(): j
        for j in range(p.getNumJoints(body, physicsClientId=client))
    }


def load_storage(
    client: int,
    model: StorageModel,
    rgba: Sequence[float],
    pose_xyz_yaw: Sequence[float],
    states: Mapping[str, float] | None = None,
    handle_rgba: Sequence[float] = HANDLE_RGBA,
) -> int:
    """Load ``model`` fixed at ``pose_xyz_yaw``, its parts at ``states`` (closed if absent); the body id.

    PyBullet's default velocity motors would hold every joint rigidly; instead each joint gets a
    zero-velocity motor whose force is the joint's friction, so a part stays where it is left (a
    flap against gravity too) and still gives way to a push stronger than that friction.

    Args:
        client: the PyBullet client.
        model: the storage model.
        rgba: the carcass's and parts' colour.
        pose_xyz_yaw: where it stands (x, y, z, yaw).
        states: each part's joint value.
        handle_rgba: the handles' colour.

    Returns:
        The body id.

    Raises:
        ValueError: a state for a part the model does not have, or out of the part's range.
    """
    states = dict(states or {})
    unknown = set(states) - {part.name for part in model.parts}
    if unknown:
        raise ValueError(f"states: {sorted(unknown)} are not parts of the {model.model}")
    x, y, z, yaw = pose_xyz_yaw
    path = urdf_file(storage_urdf(model, tuple(rgba), tuple(handle_rgba)))
    orientation = p.getQuaternionFromEuler((0.0, 0.0, yaw))
    body = p.loadURDF(str(path), (x, y, z), orientation, useFixedBase=True,
                      flags=p.URDF_USE_INERTIA_FROM_FILE, physicsClientId=client)
    links = link_indices(client, body)
    for part in model.parts:
        value = states.get(part.name, 0.0)
        if not part.lower <= value <= part.upper:
            raise ValueError(f"states.{part.name}: {value} is outside [{part.lower}, {part.upper}]")
        p.resetJointState(body, links[part.name], value, physicsClientId=client)
        p.setJointMotorControl2(body, links[part.name], p.VELOCITY_CONTROL, targetVelocity=0.0,
                                force=friction(model, part), physicsClientId=client)
    return body


def add_storage(client: int, placement: StoragePlacement, label: Label) -> tuple[StorageBody, SegLabels]:
    """Load a placed piece; its carcass carries ``label``, each part and handle a label of its own.

    Args:
        client: the PyBullet client.
        placement: the placed piece.
        label: the carcass's label.

    Returns:
        The body and its links' labels.
    """
    colour = label["colour"]
    body = load_storage(client, placement.model, COLOURS[colour], placement.pose, dict(placement.states),
                        COLOURS[handle_colour(colour)])
    links = link_indices(client, body)
    labels: SegLabels = {(body, -1): label}
    for name, part_label in part_labels(placement, colour).items():
        labels[(body, links[name])] = part_label
    return StorageBody(body, placement, links), labels


def build_scene(home: HomeSpec, client: int) -> BuiltScene:
    """Add ``home`` to the (empty) simulation ``client``; storage furniture is loaded articulated.

    Args:
        home: the home.
        client: the PyBullet client.

    Returns:
        The bodies and their labels.
    """
    built = BuiltScene()
    placed = {placement.furniture_id: placement for placement in home_storage(home)}
    for room in home.rooms:
        x0, y0, x1, y1 = room.rect
        center = ((x0 + x1) / 2, (y0 + y1) / 2, -FLOOR_THICKNESS / 2)
        body = add_box(client, center, (x1 - x0, y1 - y0, FLOOR_THICKNESS), _pale(room.floor_colour, _FLOOR_TINT))
        built.labels[(body, -1)] = room.label()
    for wall in home.walls:
        built.labels[(add_box(client, wall.center, wall.size, _WALL_RGBA), -1)] = wall.label()
    for piece in home.furniture:
        if piece.instance_id in placed:
            loaded, labels = add_storage(client, placed[piece.instance_id], piece.label())
            built.storage[piece.instance_id] = loaded
            built.labels.update(labels)
        else:
            body = add_visuals(client, piece.center, piece.size, furniture_visuals(piece))
            built.labels[(body, -1)] = piece.label()
    for item in home.objects:
        visuals = item_visuals(item)
        body = add_item(client, item) if len(visuals) == 1 else add_visuals(client, item.center, item.dims, visuals)
        built.items[item.instance_id] = body
        built.labels[(body, -1)] = item.label()
    return built


def floor_bodies(labels: SegLabels) -> set[int]:
    """The bodies the robot stands on, which never count as collisions.

    Args:
        labels: the labels by body and link.

    Returns:
        The floors' body ids.
    """
    return {body for (body, _), label in labels.items() if label["category"] == "floor"}
