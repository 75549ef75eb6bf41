"""Using the arm in a built scene: its state, running trajectories, and grasping with the gripper.

The arm's motors and physics are `worlds.arm`'s; here the arm meets the scene: contacts become
labels, a closed gripper holds the object or the storage part or handle both fingers pinch, and an
object let go of is put down straight onto whatever is under it, riding on that from then on.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pybullet as p

from worlds.arm import Touch, TrajectoryRun
from worlds.body import RobotBody
from worlds.stage import Stage
from worlds.things import Label

#: How far (rad or m) a trajectory's first sample may be from where the arm is, beyond one sample's travel.
START_TOLERANCE = 0.05


@dataclass(frozen=True)
class ArmState:
    """Where the lift and arm are and what the gripper holds.

    Args:
        positions: the lift and arm joints, in `worlds.robot_arm.arm_spec` order.
        tcp_pose: the TCP's 4x4 world pose.
        gripper_width: the gripper's opening (m).
        held: the label of what it holds, with ``link`` naming the part of a storage piece held.
        stowed: whether the arm is at its stowed pose.
    """

    positions: np.ndarray
    tcp_pose: np.ndarray
    gripper_width: float
    held: Label | None
    stowed: bool


@dataclass(frozen=True)
class TrajectoryResult:
    """How an arm trajectory went.

    Args:
        run: the arm's own account (`worlds.arm.TrajectoryRun`).
        contacts: labels of what was touched, each with ``robot_link`` (the arm's link, or
            `worlds.arm.HELD_LINK` for what the hand carries), ``link``
            (a storage part's own, else None) and ``depth``.
    """

    run: TrajectoryRun
    contacts: list[Label]


def arm_state(stage: Stage, body: RobotBody) -> ArmState:
    """The arm's state now.

    Args:
        stage: the built scene.
        body: the robot.

    Returns:
        Its joints, TCP pose, gripper opening and what it holds.
    """
    arm = body.arm
    return ArmState(arm.positions(), arm.link_pose(arm.spec.tcp_frame), arm.gripper_width(),
                    _held_label(stage, body), arm.is_stowed())


def follow_trajectory(stage: Stage, body: RobotBody, samples: np.ndarray, dt: float,
                      stop_on_contact: bool = False, stop_on_new_contact: bool = False) -> TrajectoryResult:
    """Run the lift and arm through ``samples``, one every ``dt`` seconds.

    ``samples`` must already lie within the joint limits (the command parser checks that); here
    the first sample must start where the arm is, within one sample's travel at full speed plus
    `START_TOLERANCE`. Contacts of the arm and of what it carries (`worlds.arm.Arm.touches`) with
    anything but floors, the held thing and the part whose handle is held are reported, and with
    ``stop_on_contact`` end the motion early; with ``stop_on_new_contact`` only those the arm did
    not begin the motion with do (`worlds.arm.Arm.follow`).

    Args:
        stage: the built scene.
        body: the robot.
        samples: (N, 8) joint positions in `worlds.robot_arm.arm_spec` order.
        dt: the time between samples (s).
        stop_on_contact: whether a contact ends the motion.
        stop_on_new_contact: whether a contact not there when the motion began ends it.

    Returns:
        How the run went and what the arm touched.

    Raises:
        ValueError: when the first sample is too far from where the arm is.
    """
    arm = body.arm
    samples = np.asarray(samples, dtype=float)
    reach = arm.spec.column("velocity") * dt + START_TOLERANCE
    gap = np.abs(samples[0] - arm.positions())
    if np.any(gap > reach):
        k = int(np.argmax(gap - reach))
        raise ValueError(f"samples[0][{k}]: {samples[0][k]:.4f} is {gap[k]:.4f} from where {arm.spec.names[k]} "
                         f"is ({arm.positions()[k]:.4f}); a trajectory starts where the arm is")
    grip = arm.grip
    held = set() if grip is None else {(grip.body, link) for link in grip.links}
    run = arm.follow(samples, dt, stage.riders.sync, stop_on_contact,
                     lambda other, link: (other, link) in held or other in stage.floors, stop_on_new_contact)
    contacts = [{**stage.label_of(t.body, t.link), "robot_link": t.robot_link, "depth": t.depth}
                for t in run.touches]
    return TrajectoryResult(run, contacts)


def gripper(stage: Stage, body: RobotBody, close: bool) -> Label | None:
    """Close the gripper (grasping what the fingers meet) or open it (letting go).

    Closing grasps what both fingers touch when they stop: an object, or a storage piece's part
    or handle (the deepest touch first); walls, floors, tables and carcasses are not graspable.
    Opening puts a carried object down straight onto whatever is under it.

    Args:
        stage: the built scene.
        body: the robot.
        close: True to close, False to open.

    Returns:
        The label of what the gripper holds after (`ArmState.held`), None when nothing.
    """
    arm = body.arm
    if close:
        if arm.grip is None:
            arm.move_fingers(0.0, stage.riders.sync)
            target = _graspable(stage, body, arm.touched_by_gripper())
            if target is not None:
                grasped, link = target
                tied = link >= 0
                if not tied:
                    stage.riders.lift(stage.item_of(grasped))
                arm.hold(grasped, link, tied)
        return _held_label(stage, body)
    grip = arm.let_go()
    if grip is not None and not grip.tied:
        _put_down(stage, body, grip.body)
    arm.move_fingers(arm.spec.finger_travel, stage.riders.sync)
    return None


def _held_label(stage: Stage, body: RobotBody) -> Label | None:
    grip = body.arm.grip
    return None if grip is None else stage.label_of(grip.body, grip.link)


def _graspable(stage: Stage, body: RobotBody, touches: list[Touch]) -> tuple[int, int] | None:
    """(body, link) to grasp: an object (link -1) or a storage part or handle that both fingers
    touch, the deepest touched first."""
    items = set(stage.built.items.values())
    storage = {piece.body for piece in stage.built.storage.values()}
    fingers = {body.arm.link_names[f] for f in body.arm.fingers}
    touched_by: dict[tuple[int, int], set[str]] = {}
    depth: dict[tuple[int, int], float] = {}
    for touch in touches:
        if touch.body in items:
            key = (touch.body, -1)
        elif touch.body in storage and touch.link >= 0:
            key = (touch.body, touch.link)
        else:
            continue
        touched_by.setdefault(key, set()).add(touch.robot_link)
        depth[key] = min(depth.get(key, math.inf), touch.depth)
    pinched = [key for key, links in touched_by.items() if fingers <= links]
    return min(pinched, key=depth.__getitem__, default=None)


def _put_down(stage: Stage, body: RobotBody, carried: int) -> None:
    """Let a carried object down straight until its own shape meets something (the floor level when
    nothing does), and make it ride on what it rests on. Its shape, not its box, meets what is
    below: an open-bottomed box put back over the smaller thing it covered stands on its walls
    around it, not on that thing's top. It lands on the face it was nearest standing on
    (`_settled`): a hand a degree or two off the one that lifted it tilts what it carries."""
    client = stage.client
    position, orientation = p.getBasePositionAndOrientation(carried, physicsClientId=client)
    orientation = _settled(orientation)
    with body.out_of_sight():
        drop, support = _fall(client, carried, position, orientation)
    dropped = (position[0], position[1], position[2] - drop)
    p.resetBasePositionAndOrientation(carried, dropped, orientation, physicsClientId=client)
    stage.riders.put(stage.item_of(carried), support)


def _settled(orientation: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """``orientation`` turned the least way that stands the body's axis nearest the vertical exactly
    upright (or upside down): how a thing let go of a little tilted comes to rest on a flat top."""
    rotation = np.array(p.getMatrixFromQuaternion(orientation)).reshape(3, 3)
    axis = rotation[:, int(np.argmax(np.abs(rotation[2])))]
    turn = np.cross(axis, [0.0, 0.0, math.copysign(1.0, axis[2])])
    sine = float(np.linalg.norm(turn))
    if sine < 1e-12:
        return orientation
    righting = p.getQuaternionFromAxisAngle((turn / sine).tolist(), math.asin(min(sine, 1.0)))
    return p.multiplyTransforms((0.0, 0.0, 0.0), righting, (0.0, 0.0, 0.0), orientation)[1]


#: How finely (m) a falling object's resting height is found, and the steps it first falls by.
FALL_TOLERANCE_M, FALL_STEP_M = 0.0005, 0.005


def _fall(client: int, carried: int, position: tuple[float, float, float],
          orientation: tuple[float, float, float, float]) -> tuple[float, tuple[int, int] | None]:
    """How far ``carried`` falls straight down from ``position`` before it touches another body (down
    to the floor level, z = 0), and the (body, link) it then rests on (None: the floor level)."""
    lo, hi = p.getAABB(carried, -1, physicsClientId=client)
    below = {b for b, _ in p.getOverlappingObjects((lo[0], lo[1], 0.0), hi, physicsClientId=client) or ()}
    below.discard(carried)

    def touching(drop: float) -> list[tuple[int, int]]:
        p.resetBasePositionAndOrientation(carried, (position[0], position[1], position[2] - drop), orientation,
                                          physicsClientId=client)
        return [(point[2], point[4]) for other in sorted(below)
                for point in p.getClosestPoints(carried, other, FALL_TOLERANCE_M, physicsClientId=client)]

    floor = max(0.0, lo[2])
    free, drop = 0.0, None
    for step in np.arange(FALL_STEP_M, floor + FALL_STEP_M, FALL_STEP_M):
        if touching(min(float(step), floor)):
            drop = min(float(step), floor)
            break
        free = min(float(step), floor)
    if drop is None:
        return floor, None
    while drop - free > FALL_TOLERANCE_M:
        middle = (free + drop) / 2
        if touching(middle):
            drop = middle
        else:
            free = middle
    supports = touching(free + FALL_TOLERANCE_M)
    return free, supports[0] if supports else None
