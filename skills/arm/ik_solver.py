"""Inverse kinematics and Cartesian paths for an `skills.arm.kinematics.ArmKinematics`.

IK runs damped least-squares descents (`skills.arm.ik_descent.IKDescent`); a run that stalls
restarts from a random configuration drawn from a seeded generator, so a solve is reproducible.
Targets beyond the arm's reach (`skills.arm.reach.Reach`) fail at once. Cartesian paths (along
`skills.arm.tcp_paths`) chain IK solutions, each seeded from the previous one, and fail clearly
when a waypoint is unreachable or the arm would have to jump between consecutive waypoints.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from skills.arm.frames import check_pose
from skills.arm.ik_descent import IK_MODES, IKDescent, IKMode
from skills.arm.kinematics import ArmKinematics
from skills.arm.segments import distance_to_segment


@dataclass(frozen=True)
class IKResult:
    """The outcome of one IK solve; ``q`` is the best attempt (within limits) even on failure.

    Args:
        success: whether the target was met within the tolerances.
        q: the joint positions found.
        position_error: metres from the target position.
        orientation_error: radians; in "axis" mode the angle between tool axes.
        iterations: descent steps over all runs.
        restarts: runs after the first, from random configurations.
        reason: why it failed; empty on success.
    """

    success: bool
    q: np.ndarray
    position_error: float
    orientation_error: float
    iterations: int
    restarts: int
    reason: str = ""


@dataclass(frozen=True)
class CartesianPath:
    """Joint waypoints following a list of TCP poses.

    Args:
        success: whether every pose was reached.
        q: (k, dof) waypoints starting with the start configuration; on failure those reached
            before the failing pose.
        max_position_error: metres, worst over the waypoints and the midpoints between them.
        reason: why it failed; empty on success.
        failed_index: the failing pose's index into the poses given.
    """

    success: bool
    q: np.ndarray
    max_position_error: float
    reason: str = ""
    failed_index: int | None = None


def solve_ik(kin: ArmKinematics, target_pose: np.ndarray, q_seed: np.ndarray | None = None,
             rng: np.random.Generator | None = None, *, mode: IKMode = "pose",
             tool_axis: Sequence[float] = (0.0, 0.0, 1.0), position_weight: float = 1.0,
             orientation_weight: float = 0.5, position_tolerance: float = 1e-4,
             orientation_tolerance: float = 1e-3, max_iterations: int = 100, max_restarts: int = 20,
             damping: float = 1e-6, max_step: float = 0.5) -> IKResult:
    """Joint positions that put the TCP at a target pose.

    Runs of at most ``max_iterations`` steps; a run that stalls (no 1 % progress in 10 steps)
    or runs out of steps is followed by another from a random configuration, up to
    ``max_restarts`` times.

    Args:
        kin: the arm.
        target_pose: the TCP's 4×4 target in the root frame.
        q_seed: where the first run starts (default: its `ArmKinematics.home`).
        rng: draws the restarts (default: a generator seeded with 0).
        mode: what must match (`skills.arm.ik_descent.IKMode`).
        tool_axis: the free axis of "axis" mode, in the TCP frame.
        position_weight: the weight of position errors in the descent.
        orientation_weight: the weight of rotation errors.
        position_tolerance: converged within this distance (m).
        orientation_tolerance: ... and this angle (rad).
        max_iterations: steps per run.
        max_restarts: runs after the first.
        damping: λ₀ of the damped least squares.
        max_step: caps each joint's change per iteration (rad or m).

    Returns:
        The result; on failure the best attempt and why.

    Raises:
        ValueError: a malformed argument.
    """
    target = check_pose(target_pose, "target_pose")
    if mode not in IK_MODES:
        raise ValueError(f"mode: {mode!r} is not one of {IK_MODES}")
    for field, value in (("position_weight", position_weight), ("orientation_weight", orientation_weight),
                         ("position_tolerance", position_tolerance),
                         ("orientation_tolerance", orientation_tolerance), ("max_step", max_step)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{field}: {value!r} is not a positive finite number")
    if max_iterations < 1 or max_restarts < 0:
        raise ValueError(f"max_iterations ({max_iterations}) must be ≥ 1 and "
                         f"max_restarts ({max_restarts}) ≥ 0")
    axis = np.asarray(tool_axis, dtype=float)
    if axis.shape != (3,) or not np.all(np.isfinite(axis)) or np.linalg.norm(axis) < 1e-9:
        raise ValueError(f"tool_axis: {tool_axis!r} is not a non-zero 3-vector")
    seed = kin.home() if q_seed is None else kin.checked_q(q_seed, "q_seed")
    rng = np.random.default_rng(0) if rng is None else rng

    too_far = kin.beyond_reach(target[:3, 3])
    if too_far is not None:
        distance, radius = too_far
        q = kin.clip(seed)
        position_error, orientation_error = _errors(kin, q, target, mode, axis / np.linalg.norm(axis))
        return IKResult(False, q, position_error, orientation_error, 0, 0,
                        f"target {distance:.2f} m from the shoulder, beyond the arm's {radius:.2f} m reach")

    descent = IKDescent(kin.jacobian_and_pose, kin.lower, kin.upper, target, mode, axis / np.linalg.norm(axis),
                        position_weight, orientation_weight, position_tolerance, orientation_tolerance, damping,
                        max_step)
    best: tuple[float, np.ndarray, float, float] | None = None
    iterations = 0
    for run in range(max_restarts + 1):
        start = kin.clip(seed) if run == 0 else kin.random_configuration(rng)
        converged, q, used = descent.run(start, max_iterations)
        iterations += used
        position_error, orientation_error = _errors(kin, q, target, mode, descent.axis)
        cost = descent.cost(position_error, orientation_error)
        if best is None or cost < best[0]:
            best = (cost, q, position_error, orientation_error)
        if converged:
            return IKResult(True, q, position_error, orientation_error, iterations, run)
    assert best is not None
    _, q, position_error, orientation_error = best
    return IKResult(False, q, position_error, orientation_error, iterations, max_restarts,
                    f"did not converge: best error {position_error * 100:.1f} cm / "
                    f"{math.degrees(orientation_error):.0f}°")


def plan_cartesian_path(kin: ArmKinematics, start_q: np.ndarray, poses: Sequence[np.ndarray], *,
                        mode: IKMode = "pose", max_joint_jump: float | Sequence[float] = 0.3,
                        max_deviation: float = 0.002, **ik_options: object) -> CartesianPath:
    """Joint waypoints that take the TCP through ``poses`` in turn.

    Each pose is solved from the previous solution without random restarts (a restart would
    land on another arm posture), so the arm moves continuously.

    Args:
        kin: the arm.
        start_q: where the arm starts, within the limits.
        poses: the TCP's 4×4 poses in the root frame, close together (e.g. from
            `skills.arm.tcp_paths.line_poses`).
        mode: what each IK solve must match.
        max_joint_jump: the most any joint may move between waypoints (rad or m; per joint if
            a sequence).
        max_deviation: the most the TCP may stray (m) at the midpoint of a straight joint-space
            segment from the straight TCP segment between its poses.
        **ik_options: passed on to `solve_ik` (``max_restarts`` defaults to 0).

    Returns:
        The path; on failure the waypoints reached before the first pose that is unreachable,
        needs too big a jump or strays too far (then pass denser poses).

    Raises:
        ValueError: a malformed start or pose, or a start outside the limits.
    """
    q = kin.checked_q(start_q, "start_q")
    if not kin.within_limits(q, 1e-6):
        raise ValueError(f"start_q: {np.round(q, 4).tolist()} is outside the joint limits")
    q = kin.clip(q)
    jump = np.broadcast_to(np.asarray(max_joint_jump, dtype=float), (kin.dof,))
    options: dict[str, object] = {"max_restarts": 0, **ik_options}
    previous_position = kin.forward(q)[:3, 3]
    path = [q]
    worst = 0.0
    for index, pose in enumerate(poses):
        pose = check_pose(pose, f"poses[{index}]")
        result = solve_ik(kin, pose, path[-1], mode=mode, **options)  # type: ignore[arg-type]
        reason, deviation = _path_step_problem(kin, index, path[-1], result, previous_position, pose,
                                               jump, max_deviation)
        if reason:
            return CartesianPath(False, np.array(path), worst, reason, index)
        worst = max(worst, deviation, result.position_error)
        path.append(result.q)
        previous_position = pose[:3, 3]
    return CartesianPath(True, np.array(path), worst)


def _path_step_problem(kin: ArmKinematics, index: int, previous_q: np.ndarray, result: IKResult,
                       previous_position: np.ndarray, pose: np.ndarray, jump: np.ndarray,
                       max_deviation: float) -> tuple[str, float]:
    """Why the step to pose ``index`` is unacceptable ("" if it is), and the TCP's deviation."""
    if not result.success:
        return f"pose {index} is unreachable: {result.reason}", math.inf
    step = np.abs(result.q - previous_q)
    if np.any(step > jump):
        joint = int(np.argmax(step / jump))
        return (f"pose {index} needs {kin.joint_names[joint]} to jump {step[joint]:.3f} "
                f"(limit {jump[joint]:.3f}) from the previous waypoint"), math.inf
    middle = kin.forward(0.5 * (previous_q + result.q))[:3, 3]
    deviation = distance_to_segment(middle, previous_position, pose[:3, 3])
    if deviation > max_deviation:
        return (f"on the way to pose {index} the TCP strays {deviation * 1000:.1f} mm from the "
                f"straight line (limit {max_deviation * 1000:.1f} mm): pass denser poses"), deviation
    return "", deviation


def _errors(kin: ArmKinematics, q: np.ndarray, target: np.ndarray, mode: IKMode, axis: np.ndarray
            ) -> tuple[float, float]:
    pose = kin.forward(q)
    position_error = float(np.linalg.norm(target[:3, 3] - pose[:3, 3]))
    if mode == "axis":
        return position_error, _angle_between(pose[:3, :3] @ axis, target[:3, :3] @ axis)
    return position_error, float(np.linalg.norm(pin.log3(target[:3, :3] @ pose[:3, :3].T)))


def _angle_between(a: np.ndarray, b: np.ndarray) -> float:
    return float(math.atan2(np.linalg.norm(np.cross(a, b)), float(a @ b)))
