"""How the robot of the coverage task moves: the paper's primitive actions and the steering that picks them.

A forward move is 0.25 m and a turn ±30° (`agent.lfe.task.CoverageConfig`). Turns always succeed
(the robot is round); a forward move that would put the robot's disc into an obstacle is refused,
the step spent all the same. The local planner turns toward a point ahead on its path until the
heading is within half a turn, then moves forward.
"""

from __future__ import annotations

import math
from enum import Enum

import numpy as np

from agent.lfe.task import CoverageConfig
from agent.mapping.grid import GridSpec
from agent.pose import Pose2D


class Action(Enum):
    """The paper's primitive actions (STOP aside: the episode ends when the budget or the frontiers do)."""

    FORWARD = "forward"
    TURN_LEFT = "turn_left"
    TURN_RIGHT = "turn_right"


def take_action(pose: Pose2D, action: Action, clearance_m: np.ndarray, spec: GridSpec,
                config: CoverageConfig = CoverageConfig()) -> tuple[Pose2D, bool]:
    """The pose after one action, and whether it was a forward move an obstacle stopped.

    Turns always succeed (the robot is round). A forward move is checked every half cell along
    the way (`stopping_cell`) against the true ``clearance_m``; a stopped move leaves the pose as
    it was: the step is spent all the same.

    Args:
        pose: where the robot is.
        action: what it does.
        clearance_m: metres from each cell to the nearest true obstacle (`agent.lfe.task.TrueHome.clearance_m`).
        spec: the grid of ``clearance_m``.
        config: the move's length, the turn's angle and the robot's radius.

    Returns:
        The new pose and whether the move was blocked.
    """
    if action is not Action.FORWARD:
        turn = math.radians(config.turn_deg) * (1 if action is Action.TURN_LEFT else -1)
        return Pose2D(pose.x, pose.y, _wrap(pose.yaw + turn)), False
    if stopping_cell(pose, clearance_m, spec, config) is not None:
        return pose, True
    return Pose2D(pose.x + config.forward_m * math.cos(pose.yaw), pose.y + config.forward_m * math.sin(pose.yaw),
                  pose.yaw), False


def stopping_cell(pose: Pose2D, clearance_m: np.ndarray, spec: GridSpec,
                  config: CoverageConfig = CoverageConfig()) -> tuple[int, int] | None:
    """Where a forward move from ``pose`` would first put the robot's disc into an obstacle.

    The disc fits where the true ``clearance_m`` of the cell under its centre (metres to the
    nearest occupied cell) is at least the robot's radius, and never outside the grid; positions
    are checked every half cell along the move, so no obstacle is jumped over.

    Args:
        pose: where the move starts.
        clearance_m: metres from each cell to the nearest true obstacle.
        spec: the grid of ``clearance_m``.
        config: the move's length and the robot's radius.

    Returns:
        The (row, col) of the first cell where the disc does not fit, or None when the move is free.
    """
    samples = math.ceil(config.forward_m / (spec.resolution / 2))
    along = config.forward_m * np.arange(1, samples + 1) / samples
    points = np.column_stack([pose.x + along * math.cos(pose.yaw), pose.y + along * math.sin(pose.yaw)])
    cells = spec.to_cell(points)
    inside = spec.inside(cells)
    fits = inside.copy()
    fits[inside] = clearance_m[cells[inside, 0], cells[inside, 1]] >= config.robot_radius_m
    if fits.all():
        return None
    row, col = cells[int(np.argmin(fits))]
    return int(row), int(col)


def next_action(pose: Pose2D, target: np.ndarray, config: CoverageConfig) -> Action:
    """The local planner's step: turn toward ``target`` until the heading is within half a turn of it,
    then move forward.

    Args:
        pose: where the robot is.
        target: the world point (x, y) to steer for.
        config: the turn's angle.

    Returns:
        The action to take.
    """
    error = _wrap(math.atan2(target[1] - pose.y, target[0] - pose.x) - pose.yaw)
    if abs(error) <= math.radians(config.turn_deg) / 2:
        return Action.FORWARD
    return Action.TURN_LEFT if error > 0 else Action.TURN_RIGHT


def _wrap(angle: float) -> float:
    """``angle`` in (-π, π]."""
    return math.pi - (math.pi - angle) % (2 * math.pi)
