"""Where a camera's picture begins on a plane before it, from plain arrays."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.mapping.camera import Intrinsics, nearest_seen_ahead
from worlds.robot import CameraConfig


def _looking_along_y(height: float, pitch_down_deg: float) -> np.ndarray:
    """camera_to_world of a camera at (0, 0, height) looking along +y, pitched down (OpenCV axes)."""
    s, c = math.sin(math.radians(pitch_down_deg)), math.cos(math.radians(pitch_down_deg))
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2] = (1.0, 0.0, 0.0), (0.0, -s, -c), (0.0, c, -s)
    pose[:3, 3] = (0.0, 0.0, height)
    return pose


def test_the_head_camera_misses_the_strip_of_table_before_the_robot() -> None:
    camera = CameraConfig()
    intrinsics = Intrinsics(camera.width, camera.height, *camera.intrinsics())
    pose = _looking_along_y(camera.mount_height_m, -camera.pitch_deg)
    seen_from = nearest_seen_ahead(intrinsics, pose, 0.755, np.zeros(2), np.array([0.0, 1.0]))
    below_axis = math.atan((intrinsics.height - 1 - intrinsics.cy) / intrinsics.fy)
    assert seen_from == pytest.approx((1.5 - 0.755) / math.tan(math.radians(20.0) + below_axis))
    assert 0.45 < seen_from < 0.52  # a cup 0.34 m before the robot is out of the picture
    # Looking level from below the plane, or up, the picture never reaches it.
    assert nearest_seen_ahead(intrinsics, _looking_along_y(0.5, 20.0), 0.755, np.zeros(2), np.array([0.0, 1.0])) \
        == math.inf
    assert nearest_seen_ahead(intrinsics, _looking_along_y(1.5, -60.0), 0.755, np.zeros(2), np.array([0.0, 1.0])) \
        == math.inf
