"""The robot's geometry: a holonomic disc base with a head RGB-D camera, as numbers and as URDF.

Pure maths, no simulator: the world renders with it, and the agent gets the same numbers (the
intrinsics and the camera pose) in every observation, so both sides agree on what a pixel means.

Pixel convention: pixel (row r, column c) covers [c, c + 1) x [r, r + 1) in image coordinates, so
its centre is at u = c + 0.5, v = r + 0.5 and the principal point of a centred camera is
(width / 2, height / 2). A point (X, Y, Z) in the camera frame (OpenCV: x right, y down, z ahead)
lands at u = fx X / Z + cx, v = fy Y / Z + cy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

ROBOT_RADIUS = 0.25
ROBOT_HEIGHT = 1.4
#: The base's mass. The simulator moves the base by teleporting it, so its inertial sits at the link's
#: origin: PyBullet takes a base's inertial frame for the body's frame, which thus stays base_link's.
BASE_MASS = 40.0
#: A light inertial for frames without a body (cameras, the TCP); without one PyBullet assumes 1 kg.
FRAME_INERTIAL = (
    '<inertial><origin xyz="0 0 0"/><mass value="0.01"/>'
    '<inertia ixx="1e-6" ixy="0" ixz="0" iyy="1e-6" iyz="0" izz="1e-6"/></inertial>'
)


@dataclass(frozen=True)
class CameraConfig:
    """The head camera. ``pitch_deg`` is negative when looking down; ``mount_height_m`` above the floor."""

    width: int = 320
    height: int = 240
    hfov_deg: float = 90.0
    near: float = 0.1
    far: float = 10.0
    mount_height_m: float = 1.5
    pitch_deg: float = -20.0

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or not 8 <= value <= 4096:
                raise ValueError(f"camera.{name}: {value!r} must be an integer number of pixels in 8..4096")
        for name in ("hfov_deg", "near", "far", "mount_height_m", "pitch_deg"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or isinstance(value, bool) or not math.isfinite(value):
                raise ValueError(f"camera.{name}: {value!r} must be a finite number")
        if not 10.0 < self.hfov_deg < 170.0:
            raise ValueError(f"camera.hfov_deg: {self.hfov_deg} must lie strictly between 10 and 170 degrees")
        if self.near <= 0:
            raise ValueError(f"camera.near: {self.near} must be positive")
        if self.far <= self.near:
            raise ValueError(f"camera.far: {self.far} must be greater than near ({self.near})")
        if not 0.0 < self.mount_height_m <= 3.0:
            raise ValueError(f"camera.mount_height_m: {self.mount_height_m} must lie in (0, 3] metres")
        if not -89.0 <= self.pitch_deg <= 89.0:
            raise ValueError(f"camera.pitch_deg: {self.pitch_deg} must lie in [-89, 89] degrees")

    @property
    def fx(self) -> float:
        return (self.width / 2) / math.tan(math.radians(self.hfov_deg) / 2)

    @property
    def fy(self) -> float:
        """Square pixels: the vertical field of view follows from the horizontal one and the aspect."""
        return self.fx

    @property
    def cx(self) -> float:
        return self.width / 2

    @property
    def cy(self) -> float:
        return self.height / 2

    @property
    def vfov_deg(self) -> float:
        return math.degrees(2 * math.atan((self.height / 2) / self.fy))

    def intrinsics(self) -> tuple[float, float, float, float]:
        """(fx, fy, cx, cy) in pixels.

        Returns:
            The intrinsics.
        """
        return (self.fx, self.fy, self.cx, self.cy)

    def to_dict(self) -> dict[str, Any]:
        """The camera as observations describe it.

        Returns:
            The camera's size and intrinsics.
        """
        return {
            "width": self.width,
            "height": self.height,
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            "hfov_deg": self.hfov_deg,
            "near": self.near,
            "far": self.far,
        }


def camera_pose(base_pose: tuple[float, float, float], camera: CameraConfig) -> np.ndarray:
    """The 4x4 camera-to-world transform (OpenCV axes) for a base at (x, y, yaw).

    The camera sits on the base's vertical axis at ``mount_height_m``, looking along the base's
    heading, pitched by ``pitch_deg``.

    Args:
        base_pose: the base's pose.
        camera: the camera's mount.

    Returns:
        The transform.
    """
    x, y, yaw = base_pose
    pitch = math.radians(camera.pitch_deg)
    ahead = np.array([math.cos(yaw) * math.cos(pitch), math.sin(yaw) * math.cos(pitch), math.sin(pitch)])
    right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
    down = np.cross(ahead, right)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2] = right, down, ahead
    pose[:3, 3] = (x, y, camera.mount_height_m)
    return pose


def robot_urdf(camera: CameraConfig, arm: str = "") -> str:
    """The robot description: a cylinder base, the head camera link and its optical frame.

    ``arm`` is more URDF (links and joints hanging off ``base_link``) put in after the head camera;
    `worlds.robot_arm.homebot_urdf` passes the lift, the Panda and its wrist camera here, so the
    base and head camera read the same with the arm as without it.

    Args:
        camera: the head camera.
        arm: more URDF, or "".

    Returns:
        The URDF.
    """
    body = (
        f'<origin xyz="0 0 {ROBOT_HEIGHT / 2}"/>'
        f'<geometry><cylinder radius="{ROBOT_RADIUS}" length="{ROBOT_HEIGHT}"/></geometry>'
    )
    return f"""<?xml version="1.0"?>
<robot name="homebot">
  <link name="base_link">
    <inertial><origin xyz="0 0 0"/><mass value="{BASE_MASS:g}"/>{_inertia(BASE_MASS)}</inertial>
    <visual>{body}</visual>
    <collision>{body}</collision>
  </link>
  <link name="head_camera_link">{FRAME_INERTIAL}</link>
  <joint name="head_camera_joint" type="fixed">
    <parent link="base_link"/><child link="head_camera_link"/>
    <origin xyz="0 0 {camera.mount_height_m}" rpy="0 {-math.radians(camera.pitch_deg):.6f} 0"/>
  </joint>
  <link name="head_camera_optical_frame">{FRAME_INERTIAL}</link>
  <joint name="head_camera_optical_joint" type="fixed">
    <parent link="head_camera_link"/><child link="head_camera_optical_frame"/>
    <origin xyz="0 0 0" rpy="{-math.pi / 2:.6f} 0 {-math.pi / 2:.6f}"/>
  </joint>
{arm}</robot>
"""


def _inertia(mass: float) -> str:
    """A solid cylinder's inertia the size of the base, about its axis and across it."""
    across = mass * (3 * ROBOT_RADIUS**2 + ROBOT_HEIGHT**2) / 12
    about = mass * ROBOT_RADIUS**2 / 2
    return f'<inertia ixx="{across:.4f}" ixy="0" ixz="0" iyy="{across:.4f}" iyz="0" izz="{about:.4f}"/>'


def description(camera: CameraConfig) -> dict[str, Any]:
    """What ``<ns>/world/robot/description`` answers.

    Args:
        camera: the head camera.

    Returns:
        The description.
    """
    return {
        "robot": {"radius": ROBOT_RADIUS, "height": ROBOT_HEIGHT},
        "camera": {**camera.to_dict(), "mount_height_m": camera.mount_height_m, "pitch_deg": camera.pitch_deg},
        "urdf": robot_urdf(camera),
    }
