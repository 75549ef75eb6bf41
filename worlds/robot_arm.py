"""The robot's arm: a vertical lift on the base carrying a Franka Panda with a wrist RGB-D camera.

Pure description, no simulator. `homebot_urdf` is the whole robot as one URDF string; the world
loads it into PyBullet and the agent builds its kinematics from the same text
(``pinocchio.buildModelFromXML``), so both sides move one kinematic chain. The Panda's links and
joints are pybullet_data's ``franka_panda/panda.urdf`` as they are, names kept, with mesh file names
made absolute (both PyBullet and Pinocchio find them wherever the URDF text is written); only its
``panda_grasptarget`` link is left out, in favour of our `TCP_FRAME`.

Frames (base_link: the floor under the base's axis, x ahead, z up):

- ``lift_joint`` (prismatic along z, 0 to `LIFT_TRAVEL` m) moves ``lift_link``, which starts at
  `LIFT_MOUNT`: ahead of the axis, inside the base's cylinder. ``panda_link0`` is fixed on it.
- ``panda_grasp_frame`` (`TCP_FRAME`): between the fingertips, `TCP_OFFSET` along ``panda_hand``'s
  z. The gripper approaches along its +z; the fingers close along its y.
- ``wrist_camera_link`` sits on ``panda_hand`` looking along the approach (its x = the hand's z);
  ``wrist_camera_optical_frame`` has OpenCV axes: z ahead (the approach), x right (-y of the
  hand), y down (+x of the hand).

`STOWED` folds the arm into a column inside the base's cylinder, below its top: with the arm
stowed the robot is the same disc the head camera and move_base have always known.
"""

from __future__ import annotations

import copy
import math
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pybullet_data

from worlds.robot import FRAME_INERTIAL, CameraConfig, description, robot_urdf

PANDA_DIR = Path(pybullet_data.getDataPath()) / "franka_panda"
#: Where lift_link (and panda_link0 on it) is on base_link with the lift down: 8 cm ahead of the axis.
LIFT_MOUNT = (0.08, 0.0, 0.4)
LIFT_TRAVEL = 0.6
TCP_FRAME = "panda_grasp_frame"
TCP_OFFSET = 0.1034  # Franka's own flange-to-fingertip-centre distance along the hand's z
HAND_LINK = "panda_hand"
FINGER_JOINTS = ("panda_finger_joint1", "panda_finger_joint2")
FINGER_TRAVEL = 0.04  # each finger, from closed (0) to open
WRIST_CAMERA_FRAME = "wrist_camera_optical_frame"
#: The wrist camera's centre in panda_hand's frame: beside the hand, level with the finger roots.
WRIST_CAMERA_XYZ = (-0.06, 0.0, 0.05)
#: A wide, short-range depth camera, as wrist cameras are (a RealSense D405 sees 87° across).
WRIST_CAMERA = CameraConfig(width=320, height=240, hfov_deg=87.0, near=0.02, far=3.0)
CAMERAS = ("head", "wrist")

ARM_JOINTS = ("lift_joint", *(f"panda_joint{k}" for k in range(1, 8)))
#: Folded: turned back over the base's axis (joint 1), upper arm up, forearm down beside it, hand
#: tucked in; the lift down. Every link then lies 5 cm or more inside the base's cylinder.
STOWED = (0.0, 2.88, 0.0, 0.0, -3.05, 0.0, 0.2, 0.785)
#: Trajectory limits. The Panda's datasheet allows 7.5-20 rad/s² and 3750-10000 rad/s³; a quarter
#: of that acceleration and a fiftieth of that jerk keep motions smooth enough for PyBullet's
#: position motors to track within a few millimetres. The lift moves like a household robot's.
_ACCELERATION = (0.5, 3.75, 1.875, 2.5, 3.125, 3.75, 5.0, 5.0)
_JERK = (5.0, 150.0, 75.0, 100.0, 125.0, 150.0, 200.0, 200.0)
_LIFT_VELOCITY, _LIFT_EFFORT = 0.15, 2000.0


@dataclass(frozen=True)
class ArmJoint:
    """One controllable joint and its limits (radians or metres; per s, s², s³; N·m or N)."""

    name: str
    lower: float
    upper: float
    velocity: float
    acceleration: float
    jerk: float
    effort: float


@dataclass(frozen=True)
class ArmSpec:
    """The lift and the arm as the agent plans for them: joints in order, TCP frame, stowed pose."""

    joints: tuple[ArmJoint, ...]
    tcp_frame: str
    stowed: tuple[float, ...]
    finger_joints: tuple[str, str] = FINGER_JOINTS
    finger_travel: float = FINGER_TRAVEL
    hand_link: str = HAND_LINK
    wrist_camera_frame: str = WRIST_CAMERA_FRAME

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(joint.name for joint in self.joints)

    def column(self, field: str) -> np.ndarray:
        """One limit for every joint, in order: ``arm.column("velocity")``.

        Args:
            field: the limit's name.

        Returns:
            The limits.
        """
        return np.array([getattr(joint, field) for joint in self.joints], dtype=float)

    def to_dict(self) -> dict[str, Any]:
        """The arm as the robot description tells it.

        Returns:
            The joints, the TCP frame, the stowed pose and the fingers.
        """
        return {
            "joints": [vars(joint) for joint in self.joints],
            "tcp_frame": self.tcp_frame,
            "stowed": list(self.stowed),
            "finger_joints": list(self.finger_joints),
            "finger_travel": self.finger_travel,
            "hand_link": self.hand_link,
            "wrist_camera_frame": self.wrist_camera_frame,
        }


@cache
def _panda() -> ET.Element:
    return ET.parse(PANDA_DIR / "panda.urdf").getroot()


@cache
def arm_spec() -> ArmSpec:
    """The lift and the Panda's seven joints, position, velocity and effort limits from panda.urdf.

    Returns:
        The arm's spec.
    """
    limits = {
        joint.get("name"): joint.find("limit") for joint in _panda().iter("joint") if joint.find("limit") is not None
    }
    joints = [ArmJoint("lift_joint", 0.0, LIFT_TRAVEL, _LIFT_VELOCITY, _ACCELERATION[0], _JERK[0], _LIFT_EFFORT)]
    for k, name in enumerate(ARM_JOINTS[1:], start=1):
        limit = limits[name]
        joints.append(ArmJoint(name, float(limit.get("lower")), float(limit.get("upper")),
                               float(limit.get("velocity")), _ACCELERATION[k], _JERK[k], float(limit.get("effort"))))
    return ArmSpec(tuple(joints), TCP_FRAME, STOWED)


def _xyz(values: tuple[float, ...]) -> str:
    return " ".join(f"{v:g}" for v in values)


@cache
def _panda_elements() -> str:
    """panda.urdf's links and joints (less its grasp target) as URDF text, mesh paths made absolute."""
    parts = []
    for original in _panda():
        if original.tag not in ("link", "joint") or "grasptarget" in (original.get("name") or ""):
            continue
        element = copy.deepcopy(original)
        for mesh in element.iter("mesh"):
            mesh.set("filename", str(PANDA_DIR / mesh.get("filename").removeprefix("package://")))
        parts.append(ET.tostring(element, encoding="unicode").strip())
    return "\n  ".join(parts)


def _arm_urdf() -> str:
    """Everything the arm adds to the base: lift, Panda, TCP frame and wrist camera."""
    lift = arm_spec().joints[0]
    return f"""  <link name="lift_link">
    <inertial><origin xyz="0 0 0"/><mass value="2.0"/>
      <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial>
  </link>
  <joint name="lift_joint" type="prismatic">
    <parent link="base_link"/><child link="lift_link"/>
    <origin xyz="{_xyz(LIFT_MOUNT)}" rpy="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="{lift.lower:g}" upper="{lift.upper:g}" velocity="{lift.velocity:g}" effort="{lift.effort:g}"/>
  </joint>
  <joint name="lift_panda_joint" type="fixed">
    <parent link="lift_link"/><child link="panda_link0"/><origin xyz="0 0 0" rpy="0 0 0"/>
  </joint>
  {_panda_elements()}
  <link name="{TCP_FRAME}">{FRAME_INERTIAL}</link>
  <joint name="{TCP_FRAME}_joint" type="fixed">
    <parent link="{HAND_LINK}"/><child link="{TCP_FRAME}"/><origin xyz="0 0 {TCP_OFFSET:g}" rpy="0 0 0"/>
  </joint>
  <link name="wrist_camera_link">{FRAME_INERTIAL}</link>
  <joint name="wrist_camera_joint" type="fixed">
    <parent link="{HAND_LINK}"/><child link="wrist_camera_link"/>
    <origin xyz="{_xyz(WRIST_CAMERA_XYZ)}" rpy="0 {-math.pi / 2:.6f} 0"/>
  </joint>
  <link name="{WRIST_CAMERA_FRAME}">{FRAME_INERTIAL}</link>
  <joint name="wrist_camera_optical_joint" type="fixed">
    <parent link="wrist_camera_link"/><child link="{WRIST_CAMERA_FRAME}"/>
    <origin xyz="0 0 0" rpy="{-math.pi / 2:.6f} 0 {-math.pi / 2:.6f}"/>
  </joint>
"""


def homebot_urdf(camera: CameraConfig) -> str:
    """The whole robot: the base and head camera of `worlds.robot.robot_urdf`, the lift and the arm.

    Args:
        camera: the head camera.

    Returns:
        The URDF.
    """
    return robot_urdf(camera, _arm_urdf())


def robot_description(camera: CameraConfig, wrist: CameraConfig = WRIST_CAMERA) -> dict[str, Any]:
    """What ``<ns>/world/robot/description`` answers: the base's description with the whole robot's
    URDF, the arm's joints and limits, and the wrist camera's intrinsics.

    Args:
        camera: the head camera.
        wrist: the wrist camera.

    Returns:
        The description.
    """
    return {
        **description(camera),
        "urdf": homebot_urdf(camera),
        "arm": arm_spec().to_dict(),
        "wrist_camera": {**wrist.to_dict(), "frame": WRIST_CAMERA_FRAME},
    }
