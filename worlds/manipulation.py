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
from worlds.body import OUT_OF_SIGHT, RobotBody
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
        contacts: labels of what was touched, each with ``robot_link`` (the arm's link), ``link``
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
                      stop_on_contact: bool = False) -> TrajectoryResult:
    """Run the lift and arm through ``samples``, one every ``dt`` seconds.

    ``samples`` must already lie within the joint limits (the command parser checks that); here
    the first sample must start where the arm is, within one sample's travel at full speed plus
    `START_TOLERANCE`. Contacts of the arm with anything but floors, the held thing and the part
    whose handle is held are reported, and with ``stop_on_contact`` end the motion early.

    Args:
        stage: the built scene.
        body: the robot.
        samples: (N, 8) joint positions in `worlds.robot_arm.arm_spec` order.
        dt: the time between samples (s).
        stop_on_contact: whether a contact ends the motion.

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
                     lambda other, link: (other, link) in held or other in stage.floors)
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
    """Let a carried object down straight onto the highest thing under its footprint (the floor
    level when nothing is), and make it ride on that thing."""
    client = stage.client
    lo, hi = p.getAABB(carried, -1, physicsClientId=client)
    position, orientation = p.getBasePositionAndOrientation(carried, physicsClientId=client)
    p.resetBasePositionAndOrientation(carried, OUT_OF_SIGHT, orientation, physicsClientId=client)
    with body.out_of_sight():
        xs = (*np.linspace(lo[0], hi[0], 4)[1:-1], (lo[0] + hi[0]) / 2)  # a 3 x 3 grid inside the footprint
        ys = (*np.linspace(lo[1], hi[1], 4)[1:-1], (lo[1] + hi[1]) / 2)
        starts = [(float(x), float(y), lo[2] + 0.02) for x in xs for y in ys]
        hits = p.rayTestBatch(starts, [(x, y, lo[2] - 3.0) for x, y, _ in starts], physicsClientId=client)
    found = [(hit[3][2], (hit[0], hit[1])) for hit in hits if hit[0] >= 0]
    top, support = max(found, default=(0.0, None))
    dropped = (position[0], position[1], position[2] + top - lo[2])
    p.resetBasePositionAndOrientation(carried, dropped, orientation, physicsClientId=client)
    stage.riders.put(stage.item_of(carried), support)
