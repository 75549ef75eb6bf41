"""How opening moves a door or drawer: the rigid motion that carries the closed part to open.

A drawer slides along its front's normal; a door turns about its hinge line. The same motion
carries the part's points, its handle, the TCP holding it and anything fixed to it.
"""

from __future__ import annotations

import math

import numpy as np

from agent.perception.directions import unit_vector
from agent.perception.part_geometry import PartGeometry

#: How far a part is opened when the target does not say: RoboEXP pulls drawers 0.2-0.4 m and
#: swings doors in 5° steps; 75° lets the wrist camera see past the door into the shelves. Here, not
#: with the skills, so that what an opening sweeps is planned (`agent.acsg.keep_clear`) without them.
DEFAULT_AMOUNT = {"drawer": 0.2, "door": math.radians(75.0)}


def part_motion(geometry: PartGeometry, amount: float) -> np.ndarray:
    """The rigid motion of the part opened by ``amount``: what carries the closed part's points,
    handle and anything fixed to it to where they are now.

    Args:
        geometry: the part as seen closed.
        amount: radians for a door (about its hinge axis), metres for a drawer (along its normal);
            negative to move the other way.

    Returns:
        A 4x4 world-frame transform, applied on the left.
    """
    move = np.eye(4)
    if geometry.kind == "drawer":
        move[:3, 3] = amount * geometry.normal
        return move
    assert geometry.hinge_point is not None and geometry.hinge_axis is not None
    rotation = rotation_about(geometry.hinge_axis, amount)
    move[:3, :3] = rotation
    move[:3, 3] = geometry.hinge_point - rotation @ geometry.hinge_point
    return move


def rotation_about(axis: np.ndarray, angle: float) -> np.ndarray:
    """The rotation by ``angle`` about ``axis`` (Rodrigues), the turn of a door on its hinge.

    Args:
        axis: the rotation axis (any length but zero).
        angle: radians, positive by the right-hand rule.

    Returns:
        A 3x3 rotation matrix.
    """
    k = unit_vector(axis, "axis")
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * cross @ cross


def moved_geometry(geometry: PartGeometry, amount: float) -> PartGeometry:
    """The geometry of the part after opening it, so the arm can grasp it where it now stands.

    Args:
        geometry: the part as seen closed.
        amount: how far it was opened (see `part_motion`).

    Returns:
        The geometry with handle and normal carried along; hinge, width and depth kept.
    """
    move = part_motion(geometry, amount)
    rotation = move[:3, :3]
    return PartGeometry(geometry.kind, move[:3, :3] @ geometry.handle_point + move[:3, 3],
                        rotation @ geometry.handle_axis, rotation @ geometry.normal,
                        geometry.hinge_point, geometry.hinge_axis, geometry.width, geometry.front_depth)
