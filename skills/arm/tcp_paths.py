"""Dense TCP poses along the paths a held part takes: a straight line (a drawer pulled out, an
approach along the gripper's axis) and an arc about a hinge (a door swinging). Fed to
`skills.arm.ik_solver.plan_cartesian_path`, which needs them close together.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from skills.arm.frames import check_pose


def line_poses(start: np.ndarray, end: np.ndarray, max_step: float = 0.01,
               max_angle_step: float = math.radians(3)) -> list[np.ndarray]:
    """Poses along a straight line, the rotation turning uniformly (geodesically) on the way.

    Args:
        start: the 4×4 pose the line leaves (not among the poses returned).
        end: the 4×4 pose it reaches (the last pose returned).
        max_step: the most the position moves between consecutive poses (m).
        max_angle_step: the most the rotation turns between consecutive poses (rad).

    Returns:
        At least one pose, evenly spaced from ``start`` (excluded) to ``end`` (included).

    Raises:
        ValueError: ``start`` or ``end`` is not a pose.
    """
    start, end = check_pose(start, "start"), check_pose(end, "end")
    rotation = pin.log3(end[:3, :3] @ start[:3, :3].T)
    count = max(1, math.ceil(max(np.linalg.norm(end[:3, 3] - start[:3, 3]) / max_step,
                                 np.linalg.norm(rotation) / max_angle_step)))
    poses = []
    for s in np.linspace(0.0, 1.0, count + 1)[1:]:
        pose = np.eye(4)
        pose[:3, :3] = pin.exp3(s * rotation) @ start[:3, :3]
        pose[:3, 3] = (1 - s) * start[:3, 3] + s * end[:3, 3]
        poses.append(pose)
    return poses


def arc_poses(start: np.ndarray, pivot: Sequence[float], axis: Sequence[float], angle: float,
              max_angle_step: float = math.radians(2)) -> list[np.ndarray]:
    """Poses turning ``start`` rigidly about a line: a handle's path as its door swings on the hinge.

    Args:
        start: the 4×4 pose the arc leaves (not among the poses returned).
        pivot: a point on the line (world, m).
        axis: the line's direction; the turn is right-handed about it.
        angle: how far to turn (rad).
        max_angle_step: the most the pose turns between consecutive poses (rad).

    Returns:
        At least one pose, evenly spaced from ``start`` (excluded) to the full turn (included).

    Raises:
        ValueError: ``start`` is not a pose, or ``pivot``/``axis`` are not 3-vectors (the axis non-zero).
    """
    start = check_pose(start, "start")
    pivot_ = np.asarray(pivot, dtype=float)
    axis_ = np.asarray(axis, dtype=float)
    if pivot_.shape != (3,) or axis_.shape != (3,) or np.linalg.norm(axis_) < 1e-9:
        raise ValueError(f"pivot {pivot!r} and axis {axis!r} must be 3-vectors, the axis non-zero")
    axis_ = axis_ / np.linalg.norm(axis_)
    count = max(1, math.ceil(abs(angle) / max_angle_step))
    poses = []
    for s in np.linspace(0.0, 1.0, count + 1)[1:]:
        turn = pin.exp3(s * angle * axis_)
        pose = np.eye(4)
        pose[:3, :3] = turn @ start[:3, :3]
        pose[:3, 3] = pivot_ + turn @ (start[:3, 3] - pivot_)
        poses.append(pose)
    return poses
