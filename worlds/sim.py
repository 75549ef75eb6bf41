"""One simulated home in its own PyBullet DIRECT client: reset, observe, move the base.

The robot is kinematic: moving it means teleporting its body in short steps and asking, after each
step, whether it now touches anything but the floor. PyBullet is not thread-safe, so a `World` must
be created and used from one thread only (the world server's serving thread).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import pybullet as p

from worlds.camera import Frame, render
from worlds.home import HomeSpec, generate_home
from worlds.robot import ROBOT_HEIGHT, ROBOT_RADIUS, CameraConfig
from worlds.scenario import Scenario, make_scenario
from worlds.scene import build_scene, floor_bodies
from worlds.things import Label

log = logging.getLogger(__name__)

#: The longest straight step between two collision checks, in metres.
MAX_STEP = 0.05

#: Where the robot's body waits while its head camera renders: its top would fill the view.
_OUT_OF_SIGHT = (0.0, 0.0, -100.0)
_ROBOT_RGBA = (0.3, 0.35, 0.4, 1.0)

Pose = tuple[float, float, float]


@dataclass(frozen=True)
class MoveResult:
    """Where a move_base ended, whether it got to the end of its path, and what it bumped into."""

    base_pose: Pose
    reached: bool
    contact: Label | None
    travelled_m: float
    contact_point: tuple[float, float] | None = None  # where on the obstacle the body touched it


class World:
    """A home, its scenario and the robot in it."""

    def __init__(self, camera: CameraConfig) -> None:
        self.camera = camera
        self.client = p.connect(p.DIRECT)
        self.home: HomeSpec | None = None
        self.scenario: Scenario | None = None
        self.base_pose: Pose = (0.0, 0.0, 0.0)
        self.observations = 0
        self._labels: dict[int, Label] = {}
        self._floors: set[int] = set()
        self._robot = -1

    def reset(self, seed: int, n_rooms: int | None = None) -> Scenario:
        """Build the home of ``seed`` from scratch and put the robot at the scenario's start pose."""
        home = generate_home(seed, n_rooms)
        scenario = make_scenario(home, seed)
        p.resetSimulation(physicsClientId=self.client)
        self._labels = build_scene(home, self.client)
        self._floors = floor_bodies(self._labels)
        self._robot = self._add_robot()
        self.home, self.scenario, self.observations = home, scenario, 0
        self.place(scenario.start_pose)
        log.info("home %d: %d rooms, %.1f m², question %r", seed, len(home.rooms), home.area_m2, scenario.question)
        return scenario

    def _add_robot(self) -> int:
        shape = {"radius": ROBOT_RADIUS, "physicsClientId": self.client}
        collision = p.createCollisionShape(p.GEOM_CYLINDER, height=ROBOT_HEIGHT, **shape)
        visual = p.createVisualShape(p.GEOM_CYLINDER, length=ROBOT_HEIGHT, rgbaColor=_ROBOT_RGBA, **shape)
        return p.createMultiBody(0.0, collision, visual, [0.0, 0.0, ROBOT_HEIGHT / 2], physicsClientId=self.client)

    def place(self, pose: Pose) -> None:
        """Teleport the robot, without any collision check."""
        x, y, yaw = pose
        yaw = math.atan2(math.sin(yaw), math.cos(yaw))
        orientation = p.getQuaternionFromEuler((0.0, 0.0, yaw))
        position = (x, y, ROBOT_HEIGHT / 2)
        p.resetBasePositionAndOrientation(self._robot, position, orientation, physicsClientId=self.client)
        self.base_pose = (float(x), float(y), float(yaw))

    def observe(self) -> Frame:
        """Render the head camera, with the robot's own body stepped out of the picture meanwhile."""
        self.observations += 1
        pose = self.base_pose
        p.resetBasePositionAndOrientation(self._robot, _OUT_OF_SIGHT, (0, 0, 0, 1), physicsClientId=self.client)
        try:
            return render(self.client, self.camera, pose, self._labels)
        finally:
            self.place(pose)

    def contact(self) -> Label | None:
        """The label of what the robot body touches now (the deepest contact), ignoring floors."""
        touching = self._touching()
        return None if touching is None else touching[0]

    def _touching(self) -> tuple[Label, tuple[float, float]] | None:
        """The deepest contact's label and its (x, y) on the obstacle, ignoring floors."""
        x, y, _ = self.base_pose
        lo, hi = (x - ROBOT_RADIUS, y - ROBOT_RADIUS, 0.0), (x + ROBOT_RADIUS, y + ROBOT_RADIUS, ROBOT_HEIGHT)
        deepest: tuple[float, int, tuple[float, float]] | None = None
        for body, _ in p.getOverlappingObjects(lo, hi, physicsClientId=self.client) or ():
            if body == self._robot or body in self._floors:
                continue
            for point in p.getClosestPoints(self._robot, body, 0.0, physicsClientId=self.client):
                if deepest is None or point[8] < deepest[0]:
                    deepest = (point[8], body, (float(point[6][0]), float(point[6][1])))
        return None if deepest is None else (self._labels[deepest[1]], deepest[2])

    def move_base(self, path: list[tuple[float, float]], yaw: float | None = None) -> MoveResult:
        """Follow the polyline in steps of at most `MAX_STEP`, then turn; stop before any contact."""
        x, y, heading = self.base_pose
        travelled = 0.0
        for tx, ty in path:
            length = math.hypot(tx - x, ty - y)
            steps = math.ceil(length / MAX_STEP)
            for k in range(1, steps + 1):
                nx, ny = x + (tx - x) * k / steps, y + (ty - y) * k / steps
                self.place((nx, ny, heading))
                hit = self._touching()
                if hit is not None:
                    previous = k - 1
                    self.place((x + (tx - x) * previous / steps, y + (ty - y) * previous / steps, heading))
                    return MoveResult(self.base_pose, False, hit[0], travelled, hit[1])
                travelled += length / steps
            x, y = tx, ty
        if yaw is not None:
            self.place((x, y, yaw))
            hit = self._touching()
            if hit is not None:
                self.place((x, y, heading))
                return MoveResult(self.base_pose, False, hit[0], travelled, hit[1])
        return MoveResult(self.base_pose, True, None, travelled)

    def close(self) -> None:
        if p.isConnected(self.client):
            p.disconnect(self.client)
