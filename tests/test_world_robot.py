"""The robot model: camera settings are checked, and the URDF agrees with the camera pose maths."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pybullet as p
import pytest

from worlds.robot import CameraConfig, camera_pose, robot_urdf


@pytest.mark.parametrize(
    ("field", "value"),
    [("width", 0), ("height", -5), ("width", 320.0), ("hfov_deg", 10.0), ("hfov_deg", 170.0),
     ("near", 0.0), ("far", 0.05), ("pitch_deg", -95.0), ("mount_height_m", 0.0), ("near", float("nan"))],
)
def test_bad_camera_settings_name_the_field(field: str, value: float) -> None:
    with pytest.raises(ValueError, match=f"camera.{field}"):
        CameraConfig(**{field: value})


def test_intrinsics_follow_the_field_of_view() -> None:
    camera = CameraConfig(width=640, height=480, hfov_deg=90.0)
    fx, fy, cx, cy = camera.intrinsics()
    assert (fx, fy, cx, cy) == pytest.approx((320.0, 320.0, 320.0, 240.0))
    assert camera.vfov_deg == pytest.approx(math.degrees(2 * math.atan(0.75)))


def test_camera_pose_looks_along_the_heading_and_down() -> None:
    pose = camera_pose((1.0, 2.0, math.pi / 2), CameraConfig(pitch_deg=-30.0))
    rotation = pose[:3, :3]
    assert rotation.T @ rotation == pytest.approx(np.eye(3))
    assert np.linalg.det(rotation) == pytest.approx(1.0)
    assert pose[:3, 3] == pytest.approx([1.0, 2.0, 1.5])
    assert pose[:3, 2] == pytest.approx([0.0, math.cos(math.radians(30)), -0.5])  # z ahead, pitched down
    assert pose[:3, 0] == pytest.approx([1.0, 0.0, 0.0])  # x to the right of a robot facing +y


def _rpy(rpy: list[float]) -> np.ndarray:
    r, pitch, y = rpy
    rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    ry = np.array([[math.cos(pitch), 0, math.sin(pitch)], [0, 1, 0], [-math.sin(pitch), 0, math.cos(pitch)]])
    rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    return rz @ ry @ rx


def test_urdf_optical_frame_matches_camera_pose() -> None:
    camera = CameraConfig(pitch_deg=-25.0, mount_height_m=1.4)
    transform = np.eye(4)
    for joint in ET.fromstring(robot_urdf(camera)).iter("joint"):
        origin = joint.find("origin")
        step = np.eye(4)
        step[:3, :3] = _rpy([float(v) for v in origin.get("rpy", "0 0 0").split()])
        step[:3, 3] = [float(v) for v in origin.get("xyz").split()]
        transform = transform @ step
    assert transform == pytest.approx(camera_pose((0.0, 0.0, 0.0), camera), abs=1e-5)


def test_pybullet_loads_the_urdf_with_the_camera_where_the_maths_puts_it(tmp_path) -> None:
    camera = CameraConfig()
    path = tmp_path / "homebot.urdf"
    path.write_text(robot_urdf(camera))
    client = p.connect(p.DIRECT)
    try:
        yaw = 0.7
        robot = p.loadURDF(str(path), [1.0, -2.0, 0.0], p.getQuaternionFromEuler((0, 0, yaw)), physicsClientId=client)
        names = [p.getJointInfo(robot, j, physicsClientId=client)[12].decode() for j in range(2)]
        assert names == ["head_camera_link", "head_camera_optical_frame"]
        position, orientation = p.getLinkState(robot, 1, physicsClientId=client)[4:6]
        expected = camera_pose((1.0, -2.0, yaw), camera)
        assert position == pytest.approx(expected[:3, 3], abs=1e-6)
        rotation = np.array(p.getMatrixFromQuaternion(orientation)).reshape(3, 3)
        assert rotation == pytest.approx(expected[:3, :3], abs=1e-5)
    finally:
        p.disconnect(client)
