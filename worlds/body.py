"""The robot's body in PyBullet: the whole robot loaded from its URDF, and the base's contact cylinder.

The base is kinematic: it moves only when `RobotBody.place` teleports it. Its contacts are asked
of a separate static cylinder of the same size: PyBullet wraps a URDF link's shapes in a compound
whose closest points differ from the plain cylinder's by millimetres, and the base must bump into
things exactly where it always did. The URDF base's own collisions are off, and the contact
cylinder ignores the arm inside it. The arm, stowed, stays inside that cylinder and out of every
camera's picture.

The robot's own shapes are never drawn (alpha 0, which the tiny renderer skips): no camera ever
shows the robot, which steps out of the picture for every frame, yet the renderer would still pass
the arm's meshes, about 100,000 triangles, through each frame: half of a frame's time.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from contextlib import contextmanager

import pybullet as p

from worlds.arm import Arm
from worlds.robot import ROBOT_HEIGHT, ROBOT_RADIUS, CameraConfig
from worlds.robot_arm import arm_spec, homebot_urdf
from worlds.scene import urdf_file

#: Where the robot's body waits while a camera renders or a ray is cast: out of everyone's way.
OUT_OF_SIGHT = (0.0, 0.0, -100.0)
#: The colour of the robot's own shapes: fully transparent, never drawn.
UNSEEN = (1.0, 1.0, 1.0, 0.0)

BasePose = tuple[float, float, float]


class RobotBody:
    """The robot's bodies in one simulation, loaded where the URDF puts them (the origin, facing +x),
    its arm stowed; ``pose`` is where `place` last put the base.

    Args:
        client: the PyBullet client the scene is built in.
        camera: the head camera, whose mount the URDF carries.
    """

    def __init__(self, client: int, camera: CameraConfig) -> None:
        self.client = client
        path = urdf_file(homebot_urdf(camera))
        self.robot = p.loadURDF(str(path), useFixedBase=True, flags=p.URDF_USE_INERTIA_FROM_FILE,
                                physicsClientId=client)
        p.setCollisionFilterGroupMask(self.robot, -1, 0, 0, physicsClientId=client)
        for link in {shape[1] for shape in p.getVisualShapeData(self.robot, physicsClientId=client)}:
            p.changeVisualShape(self.robot, link, rgbaColor=UNSEEN, physicsClientId=client)
        shape = p.createCollisionShape(p.GEOM_CYLINDER, radius=ROBOT_RADIUS, height=ROBOT_HEIGHT,
                                       physicsClientId=client)
        self.base = p.createMultiBody(0.0, shape, -1, [0.0, 0.0, ROBOT_HEIGHT / 2], physicsClientId=client)
        for link in range(-1, p.getNumJoints(self.robot, physicsClientId=client)):
            p.setCollisionFilterPair(self.base, self.robot, -1, link, 0, physicsClientId=client)
        self.arm = Arm(client, self.robot, arm_spec())
        self.arm.stow()
        self.pose: BasePose = (0.0, 0.0, 0.0)

    @property
    def bodies(self) -> tuple[int, int]:
        """The robot's own bodies, (whole robot, base cylinder): never obstacles to themselves.

        Returns:
            Both body ids.
        """
        return self.robot, self.base

    def place(self, pose: BasePose) -> None:
        """Teleport the robot, without any collision check; the yaw is kept in (-pi, pi].

        Args:
            pose: (x, y, yaw) of the base on the floor.
        """
        x, y, yaw = pose
        yaw = math.atan2(math.sin(yaw), math.cos(yaw))
        orientation = p.getQuaternionFromEuler((0.0, 0.0, yaw))
        p.resetBasePositionAndOrientation(self.robot, (x, y, 0.0), orientation, physicsClientId=self.client)
        p.resetBasePositionAndOrientation(self.base, (x, y, ROBOT_HEIGHT / 2), orientation,
                                          physicsClientId=self.client)
        self.pose = (float(x), float(y), float(yaw))

    @contextmanager
    def out_of_sight(self) -> Iterator[BasePose]:
        """Step the robot out of the world for a while, out of cameras' and rays' way, and back to
        where it stood afterwards (what the hand carries stays where it is).

        Returns:
            A context yielding the pose the robot comes back to.
        """
        pose = self.pose
        for body in self.bodies:
            p.resetBasePositionAndOrientation(body, OUT_OF_SIGHT, (0, 0, 0, 1), physicsClientId=self.client)
        try:
            yield pose
        finally:
            self.place(pose)
