"""URDF text and link kinematics for storage furniture (see `worlds.storage` for the frames).

The carcass is the base link; each part is a child on a revolute or prismatic joint whose frame sits
on its hinge line (doors, flaps) or the centre of its front face (drawers); each handle is a link of
its own, fixed to its part with its frame at the bar's centre. Every link has an inertial from its
boxes, so Pinocchio accepts the file and PyBullet does not invent inertias from collision shapes.
The same helpers tell the world and the tests where a part and its handle are for any joint value.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from worlds.storage import FRONT, HANDLE_BAR, HANDLE_OUT, TRAY_WALL, Box, Part, StorageModel, Vec3

#: Dark metal: the handles of a piece loaded on its own (placed pieces paint them their label's colour).
HANDLE_RGBA = (0.25, 0.25, 0.27, 1.0)
HANDLE_MASS = 0.15
_DENSITY = 500.0  # kg/m³, light chipboard
_GRAVITY = 9.81


def joint_frame(model: StorageModel, part: Part) -> tuple[Vec3, Vec3]:
    """(origin, axis) of the part's joint in the local frame: opening is positive about/along the axis.

    Args:
        model: the storage model.
        part: the part.

    Returns:
        The origin and axis.
    """
    x0, z0, x1, z1 = part.front
    y = -model.size[1] / 2
    if part.kind == "drawer":
        return ((x0 + x1) / 2, y, (z0 + z1) / 2), (0.0, -1.0, 0.0)
    if part.kind == "flap":
        return ((x0 + x1) / 2, y, z0), (1.0, 0.0, 0.0)
    if part.hinge == "left":
        return (x0, y, (z0 + z1) / 2), (0.0, 0.0, -1.0)
    return (x1, y, (z0 + z1) / 2), (0.0, 0.0, 1.0)


def part_boxes(model: StorageModel, part: Part) -> list[Box]:
    """The part's boards in the local frame, closed: its front, and a drawer's tray walls.

    Args:
        model: the storage model.
        part: the part.

    Returns:
        The boxes.
    """
    x0, z0, x1, z1 = part.front
    y = -model.size[1] / 2
    boxes = [Box.between("front", (x0, y, z0), (x1, y + FRONT, z1))]
    if part.tray is not None:
        (a, b, c), (d, e, f), t = part.tray.lo(), part.tray.hi(), TRAY_WALL
        boxes += [
            Box.between("tray_bottom", (a, b, c), (d, e, c + t)),
            Box.between("tray_left", (a, b, c + t), (a + t, e, f)),
            Box.between("tray_right", (d - t, b, c + t), (d, e, f)),
            Box.between("tray_back", (a + t, e - t, c + t), (d - t, e, f)),
        ]
    return boxes


def handle_boxes(model: StorageModel, part: Part) -> list[Box]:
    """The handle's bar and its two posts in the local frame, closed.

    Doors get a vertical bar near their free edge, drawers a horizontal one across their middle,
    flaps a horizontal one near their top edge.

    Args:
        model: the storage model.
        part: the part.

    Returns:
        The bar, then the posts.
    """
    x0, z0, x1, z1 = part.front
    width, height = x1 - x0, z1 - z0
    if part.kind == "door":
        length = float(np.clip(0.4 * height, 0.08, 0.3))
        inset = min(0.05, 0.2 * width)
        x = x1 - inset if part.hinge == "left" else x0 + inset
        z = float(np.clip(1.05, z0 + length / 2 + 0.05, z1 - length / 2 - 0.05)) if height > 1.0 else (z0 + z1) / 2
    elif part.kind == "drawer":
        length, x, z = float(np.clip(0.4 * width, 0.08, 0.3)), (x0 + x1) / 2, (z0 + z1) / 2
    else:
        length, x, z = float(np.clip(0.5 * width, 0.1, 0.4)), (x0 + x1) / 2, z1 - max(0.04, 0.1 * height)
    y = -model.size[1] / 2 - HANDLE_OUT
    vertical = part.kind == "door"
    along = np.array([0.0, 0.0, 1.0]) if vertical else np.array([1.0, 0.0, 0.0])
    across = np.array([1.0, 1.0, 0.0]) if vertical else np.array([0.0, 1.0, 1.0])
    centre = np.array([x, y, z])
    bar = Box("bar", tuple(centre), tuple(along * length + across * HANDLE_BAR))
    post_size = along * HANDLE_BAR * 0.8 + across * HANDLE_BAR * 0.8
    post_size[1] = HANDLE_OUT - HANDLE_BAR / 2
    back = np.array([0.0, (HANDLE_OUT + HANDLE_BAR / 2) / 2, 0.0])  # posts reach from the bar back to the front
    posts = [
        Box(f"post_{k}", tuple(centre + along * s * (length / 2 - HANDLE_BAR) + back), tuple(post_size))
        for k, s in enumerate((-1.0, 1.0))
    ]
    return [bar, *posts]


def part_transform(model: StorageModel, part: Part, q: float) -> np.ndarray:
    """4x4 taking a point of the closed part (local frame) to where it is at joint value ``q``.

    Args:
        model: the storage model.
        part: the part.
        q: the joint value (rad or m).

    Returns:
        The transform.
    """
    origin, axis = (np.asarray(v) for v in joint_frame(model, part))
    moved = np.eye(4)
    if part.joint == "prismatic":
        moved[:3, 3] = axis * q
        return moved
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    rotation = np.eye(3) + np.sin(q) * k + (1 - np.cos(q)) * k @ k
    moved[:3, :3] = rotation
    moved[:3, 3] = origin - rotation @ origin
    return moved


def sweep_points(model: StorageModel, part: Part, spacing: float = 0.025, steps: int = 36) -> np.ndarray:
    """Points (N, 3), local frame, that the part and its handle pass through from closed to fully open.

    A grid at most ``spacing`` apart over every board of the part and its handle, at ``steps`` + 1
    joint values: whatever holds one of these points stands in the part's way.

    Args:
        model: the storage model.
        part: the part.
        spacing: the grid's spacing (m).
        steps: the joint steps from closed to open.

    Returns:
        The points.
    """
    grids = []
    for box in (*part_boxes(model, part), *handle_boxes(model, part)):
        axes = [np.linspace(lo, hi, int(np.ceil((hi - lo) / spacing)) + 2) for lo, hi in zip(box.lo(), box.hi())]
        grids.append(np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3))
    points = np.hstack([np.concatenate(grids), np.ones((sum(len(g) for g in grids), 1))])
    values = np.linspace(part.lower, part.upper, steps + 1)
    return np.concatenate([(part_transform(model, part, q) @ points.T).T[:, :3] for q in values])


def friction(model: StorageModel, part: Part) -> float:
    """Joint friction (N·m or N): holds a flap against gravity, and lets any part rest where it is left.

    Args:
        model: the storage model.
        part: the part.

    Returns:
        The friction.
    """
    if part.kind == "drawer":
        return 4.0
    if part.kind == "door":
        return 1.0
    hinge_z = part.front[1]
    handle_z = handle_boxes(model, part)[0].center[2]
    panel = part_boxes(model, part)[0]
    torque = _mass([panel]) * _GRAVITY * panel.size[2] / 2 + HANDLE_MASS * _GRAVITY * (handle_z - hinge_z)
    return round(1.25 * torque, 3)


def storage_urdf(model: StorageModel, rgba: tuple[float, ...], handle_rgba: tuple[float, ...] = HANDLE_RGBA) -> str:
    """The piece as URDF text: a fixed-base tree carcass -> part -> handle.

    Args:
        model: the storage model.
        rgba: the carcass's and parts' colour.
        handle_rgba: the handles' colour.

    Returns:
        The URDF.
    """
    links = [_link("carcass", model.panels, (0.0, 0.0, 0.0), rgba, max(_mass(model.panels), 1.0))]
    joints = []
    for part in model.parts:
        origin, axis = joint_frame(model, part)
        boxes = part_boxes(model, part)
        links.append(_link(part.name, boxes, origin, rgba, _mass(boxes)))
        joints.append(
            f'<joint name="{part.name}_joint" type="{part.joint}"><parent link="carcass"/><child link="{part.name}"/>'
            f'<origin xyz="{_xyz(origin)}"/><axis xyz="{_xyz(axis)}"/>'
            f'<limit lower="{part.lower}" upper="{part.upper}" effort="100" velocity="1.0"/>'
            f'<dynamics damping="0.5" friction="{friction(model, part)}"/></joint>'
        )
        handle = handle_boxes(model, part)
        centre = handle[0].center
        links.append(_link(part.handle, handle, centre, handle_rgba, HANDLE_MASS))
        offset = np.subtract(centre, origin)
        joints.append(
            f'<joint name="{part.handle}_joint" type="fixed"><parent link="{part.name}"/><child link="{part.handle}"/>'
            f'<origin xyz="{_xyz(offset)}"/></joint>'
        )
    body = "\n  ".join([*links, *joints])
    return f'<?xml version="1.0"?>\n<robot name="{model.model}">\n  {body}\n</robot>\n'


def _mass(boxes: list[Box] | tuple[Box, ...]) -> float:
    return max(0.2, _DENSITY * sum(float(np.prod(b.size)) for b in boxes))


def _xyz(v: tuple[float, ...] | np.ndarray) -> str:
    return " ".join(f"{float(c):.5f}" for c in v)


def _link(name: str, boxes: Sequence[Box], frame: Sequence[float], rgba: Sequence[float], mass: float) -> str:
    """A link whose boxes are given in the local frame; ``frame`` is where the link's frame sits (closed)."""
    lo = np.min([b.lo() for b in boxes], axis=0)
    hi = np.max([b.hi() for b in boxes], axis=0)
    extent = np.maximum(hi - lo, 1e-3)
    ixx, iyy, izz = (mass / 12.0 * (extent[j] ** 2 + extent[k] ** 2) for j, k in ((1, 2), (0, 2), (0, 1)))
    com = (lo + hi) / 2 - np.asarray(frame)
    colour = " ".join(f"{c:.3f}" for c in rgba)
    shapes = []
    for box in boxes:
        origin = f'<origin xyz="{_xyz(np.subtract(box.center, frame))}"/>'
        geometry = f'<geometry><box size="{_xyz(box.size)}"/></geometry>'
        material = f'<material name="{name}_paint"><color rgba="{colour}"/></material>'
        shapes.append(f"<visual>{origin}{geometry}{material}</visual>")
        shapes.append(f"<collision>{origin}{geometry}</collision>")
    inertial = (
        f'<inertial><origin xyz="{_xyz(com)}"/><mass value="{mass:.4f}"/>'
        f'<inertia ixx="{ixx:.6f}" ixy="0" ixz="0" iyy="{iyy:.6f}" iyz="0" izz="{izz:.6f}"/></inertial>'
    )
    return f'<link name="{name}">{inertial}{"".join(shapes)}</link>'
