"""Homogeneous 4×4 poses: the base's world pose from (x, y, yaw), poses built from a rotation and
a position or shifted in the world, and the check that an array is a pose at all.
"""

from __future__ import annotations

import math

import numpy as np

from agent.pose import Pose2D


def base_transform(base_pose: Pose2D) -> np.ndarray:
    """The world pose of ``base_link``, to take world targets into the robot's root frame.

    Args:
        base_pose: where the base stands (x, y, yaw); any three numbers.

    Returns:
        The 4×4 homogeneous transform of ``base_link`` in the world frame (z up, on the floor).
    """
    x, y, yaw = (float(v) for v in base_pose)
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0, x], [s, c, 0.0, y], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def pose_at(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    """A pose from its parts, for grasps and camera views built axis by axis.

    Args:
        rotation: the 3×3 rotation.
        position: the 3-vector origin.

    Returns:
        The 4×4 homogeneous pose.
    """
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation, position
    return pose


def shifted(pose: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """The pose moved by ``offset`` in the world, its rotation kept: above a grasp, lifted off a bar.

    Args:
        pose: a 4×4 pose.
        offset: the world-frame 3-vector to add to its origin.

    Returns:
        A new 4×4 pose; ``pose`` is left as it was.
    """
    moved = pose.copy()
    moved[:3, 3] += offset
    return moved


def check_pose(pose: np.ndarray, field: str) -> np.ndarray:
    """``pose`` as a float array, checked to be a homogeneous transform, so that IK and path
    generation fail on bad input with a message naming it.

    Args:
        pose: the array to check.
        field: its name, for the error.

    Returns:
        The pose as a float (4, 4) array.

    Raises:
        ValueError: the shape is wrong, an entry is not finite, the rotation block is not a
            rotation or the last row is not [0, 0, 0, 1].
    """
    pose = np.asarray(pose, dtype=float)
    if pose.shape != (4, 4):
        raise ValueError(f"{field}: expected a 4×4 homogeneous matrix, got shape {pose.shape}")
    if not np.all(np.isfinite(pose)):
        raise ValueError(f"{field}: has non-finite entries")
    rotation = pose[:3, :3]
    if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
        raise ValueError(f"{field}: the upper-left 3×3 block is not a rotation")
    if not np.allclose(pose[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"{field}: the last row must be [0, 0, 0, 1], got {pose[3].tolist()}")
    return pose
