"""The robot's lift, arm and gripper in PyBullet: motors, trajectories, grasps.

The base is teleported (`worlds.sim`), but the arm is driven: every controllable joint has a
POSITION_CONTROL motor, and a trajectory is executed by setting targets and stepping the simulation,
so what the arm pushes or pulls (a drawer held by its handle) really moves, resisted by its joint
friction. The world has no gravity: the motors need not hold the arm up, and nothing else falls.

A grasp holds one thing in the hand in one of two ways:
- a link of an articulated body (a drawer's or door's handle) is tied to ``panda_hand`` by a fixed
  constraint at their relative pose when the gripper closed, so the part follows the hand through
  its own joint, as far as its joint limits and friction let it;
- a static body (a small object; those have no mass and take no forces) is carried kinematically:
  after every simulation step it is put back at its pose relative to the hand.
Either way the hand's and fingers' collisions with the held thing are switched off while it is
held, so the grip itself is not a contact, and the fingers hold where they met it.

After every physics step the storage parts are put back within their end stops (``end_stops``,
`worlds.end_stops.EndStops`), which PyBullet's joint limits alone do not hold against the arm.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

import numpy as np
import pybullet as p

from worlds.end_stops import EndStops
from worlds.robot_arm import ArmSpec

#: The physics step; a trajectory sample lasting dt is executed in ceil(dt / SIM_DT) equal steps.
SIM_DT = 1.0 / 240.0
#: Motor gains of PyBullet's position controller (fractions of the error corrected per step).
POSITION_GAIN, VELOCITY_GAIN = 0.3, 1.0
#: How strongly a grasped handle is tied to the hand, in N (far above any joint friction).
GRIP_FORCE = 2000.0
FINGER_FORCE, FINGER_SPEED = 40.0, 0.15
#: The fingers have stopped when they move less than this (m) in one step.
FINGER_STILL = 1e-5
FINGER_TIMEOUT_S = 1.0
#: Contacts closer than this (m, negative: penetration) count; shallower ones are touches at rest.
CONTACT_DEPTH = -1e-3
#: The robot link a carried thing's contacts are reported as (`Arm.touches`).
HELD_LINK = "held object"
#: How much deeper (m) than when a move began a contact it began with must press to stop a move
#: that stops only on new contacts (`Arm.follow`'s ``stop_on_new_contact``).
PRESSED_DEEPER_M = 2e-3
#: How close (m) a link or what the hand carries must be to a thing for a move to begin against it
#: (`Arm.touching`).
TOUCHING_M = 1e-3

Pose = np.ndarray  # 4x4
OnStep = Callable[[], None]


def _matrix(position: Iterable[float], orientation: Iterable[float]) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3] = np.array(p.getMatrixFromQuaternion(list(orientation))).reshape(3, 3)
    pose[:3, 3] = list(position)
    return pose


def _position_quaternion(pose: np.ndarray) -> tuple[list[float], list[float]]:
    """(position, quaternion xyzw) of a 4x4 rigid transform."""
    r = pose[:3, :3]
    w = math.sqrt(max(0.0, 1.0 + r[0, 0] + r[1, 1] + r[2, 2])) / 2
    x = math.copysign(math.sqrt(max(0.0, 1.0 + r[0, 0] - r[1, 1] - r[2, 2])) / 2, r[2, 1] - r[1, 2])
    y = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] + r[1, 1] - r[2, 2])) / 2, r[0, 2] - r[2, 0])
    z = math.copysign(math.sqrt(max(0.0, 1.0 - r[0, 0] - r[1, 1] + r[2, 2])) / 2, r[1, 0] - r[0, 1])
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    return pose[:3, 3].tolist(), [x / norm, y / norm, z / norm, w / norm]


@dataclass(frozen=True)
class Grip:
    """What the hand holds: a body, and its link (-1: the whole body), tied or carried. ``links``
    are the links the gripper does not collide with meanwhile: the held one and, for a handle, the
    part it is on (the fingers wrap the bar close to the front)."""

    body: int
    link: int
    tied: bool  # a constraint holds it (an articulated link); else it is carried kinematically
    links: tuple[int, ...]


@dataclass(frozen=True)
class Touch:
    """A robot link (by name) touching a link of another body, with the contact's depth (m, < 0)."""

    robot_link: str
    body: int
    link: int
    depth: float

    @property
    def between(self) -> tuple[str, int, int]:
        """What the contact is between: the robot's link, the other body and its link."""
        return self.robot_link, self.body, self.link


@dataclass(frozen=True)
class TrajectoryRun:
    """How a trajectory went: the positions reached, the worst and last tracking errors (rad or m),
    how many samples ran, whether it stopped early on a contact, and every contact met."""

    positions: np.ndarray
    max_error: float
    final_error: float
    samples_done: int
    stopped_on_contact: bool
    touches: list[Touch]


class Arm:
    """The lift, the Panda and its gripper of the robot ``body`` loaded from `homebot_urdf`.

    Args:
        client: the PyBullet client.
        body: the robot's body.
        spec: the arm's joints and limits.
    """

    def __init__(self, client: int, body: int, spec: ArmSpec) -> None:
        self.client, self.body, self.spec = client, body, spec
        joints = {}
        links = {}
        for j in range(p.getNumJoints(body, physicsClientId=client)):
            info = p.getJointInfo(body, j, physicsClientId=client)
            joints[info[1].decode()], links[info[12].decode()] = j, j
        self.links = links
        self.link_names = {index: name for name, index in links.items()}
        self.joints = [joints[name] for name in spec.names]
        self.fingers = [joints[name] for name in spec.finger_joints]
        self.hand = links[spec.hand_link]
        self.gripper_links = [self.hand, *self.fingers]
        self._forces = spec.column("effort").tolist()
        self._targets = np.array(spec.stowed, dtype=float)
        self.grip: Grip | None = None
        self._constraint: int | None = None
        self.end_stops = EndStops(client)
        self._carry: np.ndarray | None = None  # hand-to-body transform of a carried body

    # -- state ---------------------------------------------------------------------------------

    def positions(self) -> np.ndarray:
        """The arm's joint positions now (rad or m), in the spec's order.

        Returns:
            The positions.
        """
        states = p.getJointStates(self.body, self.joints, physicsClientId=self.client)
        return np.array([s[0] for s in states])

    def finger_positions(self) -> np.ndarray:
        """The two fingers' positions now (m each).

        Returns:
            The positions.
        """
        states = p.getJointStates(self.body, self.fingers, physicsClientId=self.client)
        return np.array([s[0] for s in states])

    def gripper_width(self) -> float:
        """The distance between the fingers' pads, in metres.

        Returns:
            The width.
        """
        return float(self.finger_positions().sum())

    def link_pose(self, name: str) -> Pose:
        """The 4x4 world pose of a link's URDF frame.

        Args:
            name: the link's name.

        Returns:
            The pose.
        """
        state = p.getLinkState(self.body, self.links[name], computeForwardKinematics=True, physicsClientId=self.client)
        return _matrix(state[4], state[5])

    def is_stowed(self, tolerance: float = 0.02) -> bool:
        """Whether the arm is at its stowed pose, give or take ``tolerance`` (rad or m): anywhere that
        close, it stays well inside the base's cylinder.

        Args:
            tolerance: how far each joint may be from its stowed position.

        Returns:
            Whether it is stowed.
        """
        return bool(np.all(np.abs(self.positions() - np.array(self.spec.stowed)) <= tolerance))

    # -- motion --------------------------------------------------------------------------------

    def stow(self) -> None:
        """Put the arm at its stowed pose and the fingers open at once (no motion), motors holding."""
        for joint, value in zip(self.joints, self.spec.stowed):
            p.resetJointState(self.body, joint, value, physicsClientId=self.client)
        for finger in self.fingers:
            p.resetJointState(self.body, finger, self.spec.finger_travel, physicsClientId=self.client)
        self._targets = np.array(self.spec.stowed, dtype=float)
        self._drive(self._targets, np.zeros(len(self.joints)))
        self._drive_fingers(self.spec.finger_travel)

    def _drive(self, targets: np.ndarray, velocities: np.ndarray) -> None:
        n = len(self.joints)
        p.setJointMotorControlArray(
            self.body, self.joints, p.POSITION_CONTROL, targetPositions=targets.tolist(),
            targetVelocities=velocities.tolist(), forces=self._forces,
            positionGains=[POSITION_GAIN] * n, velocityGains=[VELOCITY_GAIN] * n, physicsClientId=self.client,
        )

    def _drive_fingers(self, target: float) -> None:
        for finger in self.fingers:
            p.setJointMotorControl2(self.body, finger, p.POSITION_CONTROL, targetPosition=target,
                                    force=FINGER_FORCE, maxVelocity=FINGER_SPEED, physicsClientId=self.client)

    def _step(self, on_step: OnStep) -> None:
        """One physics step; every part stays within its end stops and a carried body keeps its place
        in the hand, then ``on_step`` runs."""
        p.stepSimulation(physicsClientId=self.client)
        self.end_stops.hold()
        self.carry()
        on_step()

    def follow(self, samples: np.ndarray, dt: float, on_step: OnStep, stop_on_contact: bool,
               ignore: Callable[[int, int], bool], stop_on_new_contact: bool = False) -> TrajectoryRun:
        """Track ``samples`` (N, joints), one every ``dt`` seconds, from where the arm is.

        Targets move linearly from one sample to the next over the sample's physics steps, with the
        matching target velocity. After each sample the robot's contacts (base link excepted, and
        those ``ignore(body, link)`` accepts) are collected; with ``stop_on_contact`` the arm stops
        at the first and holds where it is. With ``stop_on_new_contact`` it stops at the first
        contact with something it was not touching, however lightly, when the move began, or at one
        it began with pressed `PRESSED_DEEPER_M` deeper: a box carried back from the drawer it met
        starts against that drawer, and would stop at once on any contact.

        Args:
            samples: the joint positions to track.
            dt: the time between samples (s).
            on_step: called after every physics step.
            stop_on_contact: whether to stop at the first contact.
            ignore: which contacts (body, link) do not count.
            stop_on_new_contact: whether to stop at the first contact not there when the move began.

        Returns:
            How the trajectory went.
        """
        steps = max(1, math.ceil(dt / SIM_DT - 1e-9))
        p.setTimeStep(dt / steps, physicsClientId=self.client)
        previous = self._targets.copy()
        worst, done, stopped = 0.0, 0, False
        touches: dict[tuple[str, int, int], Touch] = {}
        began: dict[tuple[str, int, int], float] = {}  # what a move stopping on new contacts began against
        for touch in self.touching() if stop_on_new_contact else ():
            if not ignore(touch.body, touch.link):
                began[touch.between] = min(began.get(touch.between, 0.0), touch.depth)
        began_on = {(body, link) for _, body, link in began}
        try:
            for sample in samples:
                velocity = (sample - previous) / dt
                for k in range(1, steps + 1):
                    self._drive(previous + (sample - previous) * k / steps, velocity)
                    self._step(on_step)
                previous = sample
                self._targets = sample.copy()
                done += 1
                worst = max(worst, float(np.abs(self.positions() - sample).max()))
                new = [t for t in self.touches() if not ignore(t.body, t.link)]
                for touch in new:
                    key = touch.between
                    if key not in touches or touch.depth < touches[key].depth:
                        touches[key] = touch
                fresh = stop_on_new_contact and any((t.body, t.link) not in began_on
                                                    or t.depth < began.get(t.between, 0.0) - PRESSED_DEEPER_M
                                                    for t in new)
                if (new and stop_on_contact) or fresh:
                    stopped = True
                    self._targets = self.positions()
                    self._drive(self._targets, np.zeros(len(self.joints)))
                    break
            else:
                self._drive(self._targets, np.zeros(len(self.joints)))
        finally:
            p.setTimeStep(SIM_DT, physicsClientId=self.client)
        positions = self.positions()
        final = float(np.abs(positions - self._targets).max())
        return TrajectoryRun(positions, worst, final, done, stopped, list(touches.values()))

    def touches(self, deeper_than: float = CONTACT_DEPTH) -> list[Touch]:
        """Contacts deeper than ``deeper_than`` (by default `CONTACT_DEPTH`; 0 for every touch) in
        the last step of the robot's links (all but the base) and of what the hand carries, the
        latter as `HELD_LINK`'s.

        A carried thing is put back in the hand after every step, whatever it meets: pressed into
        a drawer or a door it would push the part on through its end stop (a box lifted inside a
        chest's lower drawer pushed the closed drawer above 55 cm into the chest, recursive 1039 of
        tuning-wide) where a real arm would feel the thing it carries meet the part.

        Args:
            deeper_than: the depth (m, negative: penetration) a contact must reach.

        Returns:
            The contacts.
        """
        found = []
        for point in p.getContactPoints(bodyA=self.body, physicsClientId=self.client):
            link, other = point[3], point[2]
            if other == self.body or link < 0:
                continue
            if point[8] <= deeper_than:
                found.append(Touch(self.link_names[link], other, point[4], float(point[8])))
        if self._carry is not None and self.grip is not None:
            for point in p.getContactPoints(bodyA=self.grip.body, physicsClientId=self.client):
                if point[2] != self.body and point[8] <= deeper_than:
                    found.append(Touch(HELD_LINK, point[2], point[4], float(point[8])))
        return found

    def touching(self) -> list[Touch]:
        """What the robot's links (all but the base) and what the hand carries touch, or come within
        `TOUCHING_M` of, as they stand now, found from their shapes rather than from the last
        step's contacts: a box just grasped from a drawer's floor, resting on it, had no contact
        reported, and its lift, pressing a millimetre into that floor as it began, stopped on it
        as on something new (recursive 1050 of tuning-wide).

        Returns:
            The touches; a depth is the distance between the shapes (m, negative: penetration).
        """
        ours = [(self.body, self.link_names)]
        if self._carry is not None and self.grip is not None:
            ours.append((self.grip.body, None))
        found = []
        for own, names in ours:
            for other in range(p.getNumBodies(physicsClientId=self.client)):
                other = p.getBodyUniqueId(other, physicsClientId=self.client)
                if other in (self.body, own):
                    continue
                for point in p.getClosestPoints(own, other, TOUCHING_M, physicsClientId=self.client):
                    if names is None:
                        found.append(Touch(HELD_LINK, other, point[4], float(point[8])))
                    elif point[3] >= 0:
                        found.append(Touch(names[point[3]], other, point[4], float(point[8])))
        return found

    # -- gripper -------------------------------------------------------------------------------

    def move_fingers(self, target: float, on_step: OnStep) -> None:
        """Drive both fingers to ``target`` (each, metres) until they get there or stop against something.

        Args:
            target: each finger's position (m).
            on_step: called after every physics step.
        """
        self._drive_fingers(target)
        last = self.finger_positions()
        for _ in range(int(FINGER_TIMEOUT_S / SIM_DT)):
            self._step(on_step)
            now = self.finger_positions()
            if np.abs(now - target).max() < FINGER_STILL or np.abs(now - last).max() < FINGER_STILL:
                break
            last = now

    def touched_by_gripper(self, margin: float = 0.003) -> list[Touch]:
        """What the hand and fingers touch now, within ``margin`` metres (closest points: no step needed).

        Args:
            margin: how near counts as touching (m).

        Returns:
            The contacts.
        """
        found = []
        for own in self.gripper_links:
            lo, hi = p.getAABB(self.body, own, physicsClientId=self.client)
            lo, hi = [v - margin for v in lo], [v + margin for v in hi]
            bodies = {b for b, _ in p.getOverlappingObjects(lo, hi, physicsClientId=self.client) or ()} - {self.body}
            for body in sorted(bodies):
                for point in p.getClosestPoints(self.body, body, margin, linkIndexA=own, physicsClientId=self.client):
                    found.append(Touch(self.link_names[own], body, point[4], float(point[8])))
        return found

    def hold(self, body: int, link: int, tied: bool) -> Grip:
        """Hold ``body``'s ``link`` where it is relative to the hand (see the module's docstring).

        Args:
            body: the body held.
            link: its link (-1: the whole body).
            tied: whether it is tied to the hand (a handle) rather than carried.

        Returns:
            The grip.
        """
        hand = p.getLinkState(self.body, self.hand, computeForwardKinematics=True, physicsClientId=self.client)
        links = (link,)
        if tied and (parent := p.getJointInfo(body, link, physicsClientId=self.client)[16]) >= 0:
            links = (link, parent)
        self.grip = Grip(body, link, tied, links)
        self._set_collisions(self.grip, False)
        if tied:
            other = p.getLinkState(body, link, computeForwardKinematics=True, physicsClientId=self.client)
            # constraint frames are relative to each link's centre of mass (getLinkState's first pose)
            relative = np.linalg.inv(_matrix(hand[0], hand[1])) @ _matrix(other[0], other[1])
            position, orientation = _position_quaternion(relative)
            self._constraint = p.createConstraint(
                self.body, self.hand, body, link, p.JOINT_FIXED, [0, 0, 0], position, [0, 0, 0],
                orientation, [0, 0, 0, 1], physicsClientId=self.client,
            )
            p.changeConstraint(self._constraint, maxForce=GRIP_FORCE, physicsClientId=self.client)
        else:
            position, orientation = p.getBasePositionAndOrientation(body, physicsClientId=self.client)
            self._carry = np.linalg.inv(self.link_pose(self.spec.hand_link)) @ _matrix(position, orientation)
        self._drive_fingers(float(self.finger_positions().mean()))
        return self.grip

    def let_go(self) -> Grip | None:
        """Stop holding (the fingers stay where they are); what was held, if anything.

        Returns:
            The grip let go, or None.
        """
        grip = self.grip
        if grip is None:
            return None
        if self._constraint is not None:
            p.removeConstraint(self._constraint, physicsClientId=self.client)
        self._set_collisions(grip, True)
        self.grip, self._constraint, self._carry = None, None, None
        return grip

    def _set_collisions(self, grip: Grip, enabled: bool) -> None:
        """Switch collisions between the gripper (hand, fingers) and the held links on or off."""
        for own in self.gripper_links:
            for link in grip.links:
                p.setCollisionFilterPair(self.body, grip.body, own, link, int(enabled), physicsClientId=self.client)

    def carry(self) -> None:
        """Put a carried body back at its place in the hand (after a step, or after the base moved)."""
        if self._carry is None or self.grip is None:
            return
        position, orientation = _position_quaternion(self.link_pose(self.spec.hand_link) @ self._carry)
        p.resetBasePositionAndOrientation(self.grip.body, position, orientation, physicsClientId=self.client)
