"""One simulated home in its own PyBullet DIRECT client: reset, observe, move the base, use the arm.

`World` composes the parts that do the work, each given what it needs: setting the scene
(`worlds.stage`), the robot's body (`worlds.body`), driving the base (`worlds.drive`), the cameras
(`worlds.sight`), storage parts and objects (`worlds.scene_state`) and the arm
(`worlds.manipulation`). The arm, stowed, stays inside the base's cylinder and out of every
camera's picture, so a robot that never uses it sees and bumps into the world exactly as the disc
alone did. PyBullet is not thread-safe, so a `World` must be created and used from one thread only
(the world server's serving thread).
"""

from __future__ import annotations

import logging
import math

import numpy as np
import pybullet as p

from worlds import manipulation, scene_state
from worlds.arm import Arm
from worlds.body import BasePose, RobotBody
from worlds.camera import Frame
from worlds.contacts import base_contact
from worlds.drive import MoveResult, move_base
from worlds.home import HomeSpec, generate_home
from worlds.manipulation import ArmState, TrajectoryResult
from worlds.robot import ROBOT_RADIUS, CameraConfig
from worlds.robot_arm import WRIST_CAMERA
from worlds.scenario import Scenario, make_scenario
from worlds.sight import observe
from worlds.stage import Stage, set_stage
from worlds.tabletop_scene import TabletopScene
from worlds.things import Label

log = logging.getLogger(__name__)

#: A tabletop robot starts this far from the table's front edge, facing it.
TABLE_GAP = 0.03


class World:
    """A home (or a tabletop), its scenario and the robot in it.

    Args:
        camera: the head camera.
        wrist_camera: the camera on the hand.
    """

    def __init__(self, camera: CameraConfig, wrist_camera: CameraConfig = WRIST_CAMERA) -> None:
        self.camera = camera
        self.wrist_camera = wrist_camera
        self.client = p.connect(p.DIRECT)
        self.home: HomeSpec | None = None
        self.tabletop: TabletopScene | None = None
        self.scenario: Scenario | None = None
        self.observations = 0
        self._stage: Stage | None = None
        self._body: RobotBody | None = None

    @property
    def ready(self) -> bool:
        """Whether a home or a tabletop has been built.

        Returns:
            True once `build` or `start_tabletop` has run.
        """
        return self.home is not None or self.tabletop is not None

    @property
    def stage(self) -> Stage:
        """The built scene: its bodies, labels and what rides on what.

        Returns:
            The stage of the last build.
        """
        assert self._stage is not None, "a scene exists only once built"
        return self._stage

    @property
    def body(self) -> RobotBody:
        """The robot's bodies in the built scene.

        Returns:
            The robot of the last build.
        """
        assert self._body is not None, "the robot exists only in a built scene"
        return self._body

    @property
    def arm(self) -> Arm:
        """The robot's lift, arm and gripper.

        Returns:
            The arm of the last build.
        """
        return self.body.arm

    @property
    def base_pose(self) -> BasePose:
        """Where the base stands.

        Returns:
            (x, y, yaw), the yaw in (-pi, pi].
        """
        return self.body.pose

    def reset(self, seed: int, n_rooms: int | None = None) -> Scenario:
        """Build the home of ``seed`` from scratch and put the robot at its scenario's start pose.

        Args:
            seed: the home's and the scenario's seed.
            n_rooms: how many rooms, else drawn from the seed.

        Returns:
            The scenario.
        """
        home = generate_home(seed, n_rooms)
        return self.start(home, make_scenario(home, seed))

    def start(self, home: HomeSpec, scenario: Scenario) -> Scenario:
        """Build ``home`` and put the robot at ``scenario``'s start pose.

        Args:
            home: the home.
            scenario: the scenario asked in it.

        Returns:
            ``scenario``.
        """
        self.build(home)
        self.scenario = scenario
        self.place(scenario.start_pose)
        log.info("home %d: %d rooms, %.1f m², question %r", home.seed, len(home.rooms), home.area_m2, scenario.question)
        return scenario

    def build(self, home: HomeSpec) -> None:
        """Replace the simulation with ``home`` (its storage furniture articulated) and the robot,
        which stands at the origin until placed.

        Args:
            home: the home.
        """
        self._stage, self._body = set_stage(self.client, home, self.camera)
        self.home, self.tabletop, self.scenario, self.observations = home, None, None, 0

    def start_tabletop(self, scene: TabletopScene, base_pose: BasePose | None = None) -> BasePose:
        """Replace the simulation with a tabletop ``scene`` and the robot.

        Args:
            scene: the tabletop.
            base_pose: where the robot stands; by default in front of the table's middle, facing it (+y).

        Returns:
            The robot's pose.
        """
        self._stage, self._body = set_stage(self.client, scene, self.camera)
        self.home, self.tabletop, self.scenario, self.observations = None, scene, None, 0
        if base_pose is None:
            base_pose = (0.0, -(scene.table_size[1] / 2 + ROBOT_RADIUS + TABLE_GAP), math.pi / 2)
        self.place(base_pose)
        return self.base_pose

    def place(self, pose: BasePose) -> None:
        """Teleport the robot, without any collision check.

        Args:
            pose: (x, y, yaw).
        """
        self.body.place(pose)

    def observe(self, camera: str = "head") -> Frame:
        """Render the head or the wrist camera (`worlds.sight.observe`), and count the frame.

        Args:
            camera: ``"head"`` or ``"wrist"``.

        Returns:
            The frame.
        """
        frame = observe(self.stage, self.body, camera, self.camera, self.wrist_camera)
        self.observations += 1
        return frame

    def contact(self) -> Label | None:
        """What the robot's base touches now (the deepest contact), ignoring floors.

        Returns:
            Its label, or None.
        """
        touching = base_contact(self.stage, self.body)
        return None if touching is None else touching[0]

    def move_base(self, path: list[tuple[float, float]], yaw: float | None = None) -> MoveResult:
        """Drive along ``path``, then turn to ``yaw`` (`worlds.drive.move_base`).

        Args:
            path: (x, y) waypoints.
            yaw: the final heading, if any.

        Returns:
            Where the base stopped and why.
        """
        return move_base(self.stage, self.body, path, yaw)

    def set_part_state(self, furniture_id: int, part_name: str, value: float) -> None:
        """Set a storage part's joint (`worlds.scene_state.set_part_state`).

        Args:
            furniture_id: the storage piece.
            part_name: the part.
            value: the joint value.
        """
        scene_state.set_part_state(self.stage, furniture_id, part_name, value)

    def object_position(self, instance_id: int) -> tuple[float, float, float]:
        """Where a small object's centre is now.

        Args:
            instance_id: the object.

        Returns:
            (x, y, z).
        """
        return scene_state.object_position(self.stage, instance_id)

    def part_states(self) -> dict[int, dict[str, float]]:
        """Every storage part's joint value now.

        Returns:
            Furniture id -> part name -> joint value.
        """
        return scene_state.part_states(self.stage)

    def arm_state(self) -> ArmState:
        """The arm's joints, TCP pose, gripper opening and what it holds.

        Returns:
            The arm's state.
        """
        return manipulation.arm_state(self.stage, self.body)

    def follow_trajectory(self, samples: np.ndarray, dt: float, stop_on_contact: bool = False,
                          stop_on_new_contact: bool = False) -> TrajectoryResult:
        """Run the arm through ``samples`` (`worlds.manipulation.follow_trajectory`).

        Args:
            samples: (N, 8) joint positions.
            dt: seconds between samples.
            stop_on_contact: whether a contact ends the motion.
            stop_on_new_contact: whether a contact not there when the motion began ends it.

        Returns:
            How it went.
        """
        return manipulation.follow_trajectory(self.stage, self.body, samples, dt, stop_on_contact, stop_on_new_contact)

    def gripper(self, close: bool) -> Label | None:
        """Close or open the gripper (`worlds.manipulation.gripper`).

        Args:
            close: True to close, False to open.

        Returns:
            What it holds after.
        """
        return manipulation.gripper(self.stage, self.body, close)

    def close(self) -> None:
        """Disconnect the physics client."""
        if p.isConnected(self.client):
            p.disconnect(self.client)
