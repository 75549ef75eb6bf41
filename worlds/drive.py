"""Driving the kinematic base: teleporting the robot in short steps, stopping before any contact.

After each step the base's cylinder is asked whether it touches anything but the floor and, when
the arm is out or holds something, the arm and what it holds are asked too (`worlds.contacts`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from worlds.body import BasePose, RobotBody
from worlds.contacts import Contact, arm_contact, base_contact
from worlds.stage import Stage
from worlds.things import Label

#: The longest straight step between two collision checks, in metres.
MAX_STEP = 0.05


@dataclass(frozen=True)
class MoveResult:
    """Where a move_base ended, whether it got to the end of its path, and what it bumped into.

    Args:
        base_pose: (x, y, yaw) where the base stands now.
        reached: whether it drove the whole path (and turned).
        contact: the label of what it bumped into, if anything.
        travelled_m: how far it drove along the path.
        contact_point: where on the obstacle the robot touched it.
    """

    base_pose: BasePose
    reached: bool
    contact: Label | None
    travelled_m: float
    contact_point: tuple[float, float] | None = None


def move_base(stage: Stage, body: RobotBody, path: list[tuple[float, float]], yaw: float | None) -> MoveResult:
    """Follow the polyline in steps of at most `MAX_STEP`, then turn; stop before any contact.

    A stowed arm lies inside the base's cylinder, so only the base is checked; an arm that is
    out, or holds something, is checked too, and what it carries goes along. A grasped handle
    ties the robot to its furniture: the base does not move until the gripper opens.

    Args:
        stage: the built scene.
        body: the robot, driven from where it stands.
        path: the (x, y) waypoints.
        yaw: the heading to turn to at the end, if any.

    Returns:
        Where the base stopped and why.

    Raises:
        ValueError: when the gripper holds a handle.
    """
    held = body.arm.grip
    if held is not None and held.tied:
        label = stage.label_of(held.body, held.link)
        raise ValueError(f"move_base: the gripper holds {label['category']} {label['id']}; open it first")
    arm_out = held is not None or not body.arm.is_stowed()
    x, y, heading = body.pose
    travelled = 0.0
    for tx, ty in path:
        length = math.hypot(tx - x, ty - y)
        steps = math.ceil(length / MAX_STEP)
        for k in range(1, steps + 1):
            nx, ny = x + (tx - x) * k / steps, y + (ty - y) * k / steps
            hit = _step_to(stage, body, (nx, ny, heading), arm_out)
            if hit is not None:
                previous = k - 1
                _step_to(stage, body, (x + (tx - x) * previous / steps, y + (ty - y) * previous / steps, heading),
                         False)
                return MoveResult(body.pose, False, hit[0], travelled, hit[1])
            travelled += length / steps
        x, y = tx, ty
    if yaw is not None:
        hit = _step_to(stage, body, (x, y, yaw), arm_out)
        if hit is not None:
            _step_to(stage, body, (x, y, heading), False)
            return MoveResult(body.pose, False, hit[0], travelled, hit[1])
    return MoveResult(body.pose, True, None, travelled)


def _step_to(stage: Stage, body: RobotBody, pose: BasePose, arm_out: bool) -> Contact | None:
    """Teleport the robot (and what it carries) to ``pose``; what it touches there, if anything."""
    body.place(pose)
    body.arm.carry()
    hit = base_contact(stage, body)
    if hit is None and arm_out:
        hit = arm_contact(stage, body)
    return hit
