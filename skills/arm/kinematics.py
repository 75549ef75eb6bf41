"""The arm's kinematics: forward kinematics, Jacobians and inverse kinematics with Pinocchio.

The controlled joints (the lift and the arm) form the configuration vector ``q`` in the order the
caller names them; every other joint of the URDF (the fingers, a mobile base) is locked at a fixed
value, so one model serves whether the URDF is the bare arm or the whole robot. Poses are 4×4
homogeneous matrices of the TCP frame in the model's root frame (the URDF's root link).

IK is damped least squares on a world-aligned error: the position error p* − p in metres and the
rotation error log3(R* Rᵀ) in radians, so the tolerances and the reported errors are plain
distances and angles, and a position-only or free-tool-axis request simply drops or projects rows.
The damping follows Sugihara (2011): λ = ½‖e‖² + λ₀, large far from the target (small, safe steps)
and vanishing near it (Gauss–Newton's fast convergence). Joint limits are enforced every iteration
by clamping, with joints pinned at a limit taken out of the step that would push them past it, so
the other joints keep moving. A run that stalls restarts from a random configuration drawn from a
seeded generator, so a solve is reproducible.

Cartesian paths (drawers pulled along a line, doors swung along an arc) chain IK solutions, each
seeded from the previous one, and fail clearly when a waypoint is unreachable or the arm would have
to jump between consecutive waypoints.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal

import numpy as np
import pinocchio as pin
from scipy.optimize import lsq_linear

IKMode = Literal["pose", "position", "axis"]
"""What IK must match: the full pose; the position only; or the position and the tool axis, leaving
the rotation about that axis free (a symmetric grasp, a top-down pick)."""

_MODES = ("pose", "position", "axis")


@dataclass(frozen=True)
class IKResult:
    """The outcome of one IK solve; ``q`` is the best attempt (within limits) even on failure."""

    success: bool
    q: np.ndarray
    position_error: float  # metres from the target position
    orientation_error: float  # radians; in "axis" mode the angle between tool axes
    iterations: int  # over all runs
    restarts: int  # runs after the first, from random configurations
    reason: str = ""  # why it failed; empty on success


@dataclass(frozen=True)
class CartesianPath:
    """Joint waypoints following a list of TCP poses; ``q`` starts with the start configuration.

    On failure ``q`` holds the waypoints reached before the failing pose ``failed_index``.
    """

    success: bool
    q: np.ndarray  # (k, dof)
    max_position_error: float  # metres, worst over the waypoints and the midpoints between them
    reason: str = ""
    failed_index: int | None = None  # index into the poses given


class ArmKinematics:
    """Forward and inverse kinematics of a serial chain in a URDF, through the chosen joints.

    ``joints`` name the controlled joints (1-DoF revolute or prismatic, with finite limits) in the
    order of ``q``; ``fixed`` gives positions for other 1-DoF joints, which otherwise sit at their
    neutral position (zero, clipped into their limits).
    """

    def __init__(self, urdf_xml: str, joints: Sequence[str], tcp_frame: str,
                 fixed: Mapping[str, float] | None = None) -> None:
        full = pin.buildModelFromXML(urdf_xml)
        self.joint_names: tuple[str, ...] = tuple(joints)
        self.tcp_frame = tcp_frame
        if not self.joint_names:
            raise ValueError("joints: at least one controlled joint is needed")
        if len(set(self.joint_names)) != len(self.joint_names):
            raise ValueError(f"joints: names repeat in {list(self.joint_names)}")
        known = list(full.names)[1:]
        for name in self.joint_names:
            if name not in known:
                raise ValueError(f"joints: {name!r} is not a joint of the URDF (it has {known})")
        if not full.existFrame(tcp_frame):
            raise ValueError(f"tcp_frame: {tcp_frame!r} is not a link or frame of the URDF")
        self.model = _reduced_model(full, self.joint_names, dict(fixed or {}))
        self.data = self.model.createData()
        self._frame = self.model.getFrameId(tcp_frame)
        self._q_index = np.array([self.model.idx_qs[self.model.getJointId(n)] for n in self.joint_names])
        self._v_index = np.array([self.model.idx_vs[self.model.getJointId(n)] for n in self.joint_names])
        self._qm = pin.neutral(self.model)
        self.lower = self.model.lowerPositionLimit[self._q_index].copy()
        self.upper = self.model.upperPositionLimit[self._q_index].copy()
        self.velocity_limits = self.model.velocityLimit[self._v_index].copy()
        for name, lo, hi in zip(self.joint_names, self.lower, self.upper, strict=True):
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ValueError(f"joints: {name!r} needs finite limits with lower ≤ upper, got [{lo}, {hi}]")
        self._reach = _Reach.of(self)

    @property
    def dof(self) -> int:
        return len(self.joint_names)

    @property
    def reach(self) -> float:
        """An upper bound on the TCP's distance from the shoulder (the first revolute joint)."""
        return self._reach.radius

    def home(self) -> np.ndarray:
        """The middle of every joint's range: a neutral seed far from all limits."""
        return 0.5 * (self.lower + self.upper)

    def random_configuration(self, rng: np.random.Generator) -> np.ndarray:
        return rng.uniform(self.lower, self.upper)

    def clip(self, q: np.ndarray) -> np.ndarray:
        return np.clip(q, self.lower, self.upper)

    def within_limits(self, q: np.ndarray, tolerance: float = 1e-9) -> bool:
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= self.lower - tolerance) and np.all(q <= self.upper + tolerance))

    def forward(self, q: np.ndarray) -> np.ndarray:
        """The 4×4 pose of the TCP in the root frame."""
        pin.framesForwardKinematics(self.model, self.data, self._model_q(q))
        return self.data.oMf[self._frame].homogeneous.copy()

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """The 6×dof Jacobian of the TCP: rows (linear velocity of its origin, angular velocity), both
        in root-frame axes; columns in the order of ``joints``."""
        return self._jacobian(self._model_q(q))[0]

    def solve_ik(self, target_pose: np.ndarray, q_seed: np.ndarray | None = None,
                 rng: np.random.Generator | None = None, *, mode: IKMode = "pose",
                 tool_axis: Sequence[float] = (0.0, 0.0, 1.0), position_weight: float = 1.0,
                 orientation_weight: float = 0.5, position_tolerance: float = 1e-4,
                 orientation_tolerance: float = 1e-3, max_iterations: int = 100, max_restarts: int = 20,
                 damping: float = 1e-6, max_step: float = 0.5) -> IKResult:
        """Joint positions that put the TCP at ``target_pose``, starting from ``q_seed``.

        Runs of at most ``max_iterations`` steps; a run that stalls (no 1 % progress in 10 steps)
        or runs out of steps is followed by another from a random configuration, up to
        ``max_restarts`` times. ``rng`` draws those (default: a generator seeded with 0).
        ``tool_axis`` is the free axis of "axis" mode, in the TCP frame. ``max_step`` caps each
        joint's change per iteration (rad or m).
        """
        target = _check_pose(target_pose, "target_pose")
        if mode not in _MODES:
            raise ValueError(f"mode: {mode!r} is not one of {_MODES}")
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
        seed = self.home() if q_seed is None else self._check_q(q_seed, "q_seed")
        rng = np.random.default_rng(0) if rng is None else rng

        too_far = self._reach.excess(target[:3, 3])
        if too_far is not None:
            distance, radius = too_far
            q = self.clip(seed)
            position_error, orientation_error = self._errors(q, target, mode, axis / np.linalg.norm(axis))
            return IKResult(False, q, position_error, orientation_error, 0, 0,
                            f"target {distance:.2f} m from the shoulder, beyond the arm's {radius:.2f} m reach")

        problem = _IKProblem(self, target, mode, axis / np.linalg.norm(axis), position_weight, orientation_weight,
                             position_tolerance, orientation_tolerance, damping, max_step)
        best: tuple[float, np.ndarray, float, float] | None = None
        iterations = 0
        for run in range(max_restarts + 1):
            start = self.clip(seed) if run == 0 else self.random_configuration(rng)
            converged, q, used = problem.run(start, max_iterations)
            iterations += used
            position_error, orientation_error = self._errors(q, target, mode, problem.axis)
            cost = problem.cost(position_error, orientation_error)
            if best is None or cost < best[0]:
                best = (cost, q, position_error, orientation_error)
            if converged:
                return IKResult(True, q, position_error, orientation_error, iterations, run)
        assert best is not None
        _, q, position_error, orientation_error = best
        return IKResult(False, q, position_error, orientation_error, iterations, max_restarts,
                        f"did not converge: best error {position_error * 100:.1f} cm / "
                        f"{math.degrees(orientation_error):.0f}°")

    def plan_cartesian_path(self, start_q: np.ndarray, poses: Sequence[np.ndarray], *, mode: IKMode = "pose",
                            max_joint_jump: float | Sequence[float] = 0.3, max_deviation: float = 0.002,
                            **ik_options: object) -> CartesianPath:
        """Joint waypoints that take the TCP through ``poses`` in turn, from ``start_q``.

        Each pose is solved from the previous solution without random restarts (a restart would
        land on another arm posture), so the arm moves continuously. It fails at the first pose
        that is unreachable, needs some joint to move more than ``max_joint_jump`` (rad or m;
        per joint if a sequence), or whose straight joint-space segment from the previous waypoint
        lets the TCP stray more than ``max_deviation`` metres from the straight TCP segment at its
        midpoint (then the poses are too far apart: pass denser poses, e.g. from `line_poses`).
        """
        q = self._check_q(start_q, "start_q")
        if not self.within_limits(q, 1e-6):
            raise ValueError(f"start_q: {np.round(q, 4).tolist()} is outside the joint limits")
        q = self.clip(q)
        jump = np.broadcast_to(np.asarray(max_joint_jump, dtype=float), (self.dof,))
        options: dict[str, object] = {"max_restarts": 0, **ik_options}
        previous_position = self.forward(q)[:3, 3]
        path = [q]
        worst = 0.0
        for index, pose in enumerate(poses):
            pose = _check_pose(pose, f"poses[{index}]")
            result = self.solve_ik(pose, path[-1], mode=mode, **options)  # type: ignore[arg-type]
            reason, deviation = self._path_step_problem(index, path[-1], result, previous_position, pose,
                                                        jump, max_deviation)
            if reason:
                return CartesianPath(False, np.array(path), worst, reason, index)
            worst = max(worst, deviation, result.position_error)
            path.append(result.q)
            previous_position = pose[:3, 3]
        return CartesianPath(True, np.array(path), worst)

    # -- internals --------------------------------------------------------------------------------

    def _path_step_problem(self, index: int, previous_q: np.ndarray, result: IKResult,
                           previous_position: np.ndarray, pose: np.ndarray, jump: np.ndarray,
                           max_deviation: float) -> tuple[str, float]:
        """Why the step to pose ``index`` is unacceptable ("" if it is), and the TCP's deviation."""
        if not result.success:
            return f"pose {index} is unreachable: {result.reason}", math.inf
        step = np.abs(result.q - previous_q)
        if np.any(step > jump):
            joint = int(np.argmax(step / jump))
            return (f"pose {index} needs {self.joint_names[joint]} to jump {step[joint]:.3f} "
                    f"(limit {jump[joint]:.3f}) from the previous waypoint"), math.inf
        middle = self.forward(0.5 * (previous_q + result.q))[:3, 3]
        deviation = _distance_to_segment(middle, previous_position, pose[:3, 3])
        if deviation > max_deviation:
            return (f"on the way to pose {index} the TCP strays {deviation * 1000:.1f} mm from the "
                    f"straight line (limit {max_deviation * 1000:.1f} mm): pass denser poses"), deviation
        return "", deviation

    def _check_q(self, q: np.ndarray, field: str) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (self.dof,):
            raise ValueError(f"{field}: expected shape ({self.dof},) for joints {list(self.joint_names)}, "
                             f"got {q.shape}")
        if not np.all(np.isfinite(q)):
            raise ValueError(f"{field}: has non-finite values {q.tolist()}")
        return q

    def _model_q(self, q: np.ndarray) -> np.ndarray:
        qm = self._qm.copy()
        qm[self._q_index] = self._check_q(q, "q")
        return qm

    def _jacobian(self, qm: np.ndarray) -> tuple[np.ndarray, pin.SE3]:
        """The user-ordered LOCAL_WORLD_ALIGNED Jacobian and the TCP pose, in one kinematics pass."""
        full = pin.computeFrameJacobian(self.model, self.data, qm, self._frame, pin.LOCAL_WORLD_ALIGNED)
        return full[:, self._v_index], self.data.oMf[self._frame]

    def _errors(self, q: np.ndarray, target: np.ndarray, mode: IKMode, axis: np.ndarray) -> tuple[float, float]:
        pose = self.forward(q)
        position_error = float(np.linalg.norm(target[:3, 3] - pose[:3, 3]))
        if mode == "axis":
            return position_error, _angle_between(pose[:3, :3] @ axis, target[:3, :3] @ axis)
        return position_error, float(np.linalg.norm(pin.log3(target[:3, :3] @ pose[:3, :3].T)))


class _IKProblem:
    """One IK target with its weights and tolerances; `run` does one damped least-squares descent."""

    def __init__(self, kin: ArmKinematics, target: np.ndarray, mode: IKMode, axis: np.ndarray,
                 position_weight: float, orientation_weight: float, position_tolerance: float,
                 orientation_tolerance: float, damping: float, max_step: float) -> None:
        self.kin, self.mode, self.axis = kin, mode, axis
        self.p_target, self.r_target = target[:3, 3].copy(), target[:3, :3].copy()
        self.axis_target = self.r_target @ axis
        self.wp, self.wr = position_weight, orientation_weight
        self.tol_p, self.tol_r = position_tolerance, orientation_tolerance
        self.damping, self.max_step = damping, max_step

    def cost(self, position_error: float, orientation_error: float) -> float:
        """Which of two failed attempts is better: errors in units of their tolerances."""
        rotation = 0.0 if self.mode == "position" else orientation_error / self.tol_r
        return position_error / self.tol_p + rotation

    def run(self, q: np.ndarray, max_iterations: int) -> tuple[bool, np.ndarray, int]:
        kin = self.kin
        qm = kin._qm.copy()
        lower, upper = kin.lower, kin.upper
        best_energy, best_at = math.inf, 0
        for iteration in range(max_iterations):
            qm[kin._q_index] = q
            jacobian, pose = kin._jacobian(qm)
            error, rows, converged = self._residual(jacobian, pose)
            if converged:
                return True, q, iteration + 1
            energy = 0.5 * float(error @ error)
            if energy < 0.99 * best_energy:
                best_energy, best_at = energy, iteration
            elif iteration - best_at >= 10:
                return False, q, iteration + 1
            step = self._step(rows, error, energy)
            pinned = ((q <= lower) & (step < 0)) | ((q >= upper) & (step > 0))
            if np.any(pinned):  # joints at a limit pushing outward: solve without them
                step = self._step(rows * ~pinned, error, energy)
            largest = float(np.max(np.abs(step)))
            if largest > self.max_step:
                step *= self.max_step / largest
            q = np.clip(q + step, lower, upper)
        qm[kin._q_index] = q
        jacobian, pose = kin._jacobian(qm)
        return self._residual(jacobian, pose)[2], q, max_iterations

    def _residual(self, jacobian: np.ndarray, pose: pin.SE3) -> tuple[np.ndarray, np.ndarray, bool]:
        """The weighted error e and the matching rows J of the linearisation e(q + dq) ≈ e − J dq."""
        position_error = self.p_target - pose.translation
        close = float(np.linalg.norm(position_error)) <= self.tol_p
        if self.mode == "position":
            return self.wp * position_error, self.wp * jacobian[:3], close
        rotation = pose.rotation
        if self.mode == "pose":
            r_error = self.r_target @ rotation.T
            rotation_error = pin.log3(r_error)
            angle = float(np.linalg.norm(rotation_error))
            rotation_rows = pin.Jlog3(r_error) @ jacobian[3:]
        else:
            axis = rotation @ self.axis
            rotation_error = _rotation_vector(axis, self.axis_target)
            angle = float(np.linalg.norm(rotation_error))
            rotation_rows = (np.eye(3) - np.outer(axis, axis)) @ jacobian[3:]  # spinning about the axis is free
        error = np.concatenate([self.wp * position_error, self.wr * rotation_error])
        rows = np.vstack([self.wp * jacobian[:3], self.wr * rotation_rows])
        return error, rows, close and angle <= self.tol_r

    def _step(self, rows: np.ndarray, error: np.ndarray, energy: float) -> np.ndarray:
        """Levenberg–Marquardt step with Sugihara's damping λ = E + λ₀."""
        normal = rows.T @ rows
        normal[np.diag_indices_from(normal)] += energy + self.damping
        return np.linalg.solve(normal, rows.T @ error)


@dataclass(frozen=True)
class _Reach:
    """Where the shoulder can be and how far the TCP can get from it, to reject hopeless targets.

    The shoulder is the first controlled revolute joint on the chain to the TCP. Prismatic joints
    above it (the lift) move it over a parallelotope ``base + directions · t``, t ∈ [0, 1]ᵏ; the
    TCP is never further from it than the sum of the link offsets (and prismatic strokes) below it.
    """

    base: np.ndarray | None  # None: no revolute joint on the chain, no reach check
    directions: np.ndarray  # (3, k)
    radius: float

    @staticmethod
    def of(kin: ArmKinematics) -> _Reach:
        model = kin.model
        frame = model.frames[kin._frame]
        chain = []
        joint = frame.parentJoint
        while joint > 0:
            chain.append(joint)
            joint = model.parents[joint]
        chain.reverse()
        controlled = {model.getJointId(name): i for i, name in enumerate(kin.joint_names)}
        revolute = [j for j in chain if j in controlled and _kind(model.joints[j]) == "revolute"]
        if not revolute:
            return _Reach(None, np.zeros((3, 0)), math.inf)
        shoulder = revolute[0]
        below = chain[chain.index(shoulder) + 1:]
        radius = float(np.linalg.norm(frame.placement.translation))
        for j in below:
            radius += float(np.linalg.norm(model.jointPlacements[j].translation))
            if _kind(model.joints[j]) == "prismatic":
                radius += float(np.max(np.abs([model.lowerPositionLimit[model.idx_qs[j]],
                                               model.upperPositionLimit[model.idx_qs[j]]])))
        lifts = [controlled[j] for j in chain[:chain.index(shoulder)] if j in controlled]
        data = model.createData()

        def shoulder_at(q: np.ndarray) -> np.ndarray:
            qm = kin._qm.copy()
            qm[kin._q_index] = q
            pin.forwardKinematics(model, data, qm)
            return data.oMi[shoulder].translation.copy()

        q = kin.lower.copy()
        base = shoulder_at(q)
        directions = []
        for i in lifts:
            moved = q.copy()
            moved[i] = kin.upper[i]
            directions.append(shoulder_at(moved) - base)
        return _Reach(base, np.array(directions).T.reshape(3, len(lifts)), radius)

    def excess(self, point: np.ndarray) -> tuple[float, float] | None:
        """(distance from the nearest shoulder position, reach) when the point is beyond reach."""
        if self.base is None:
            return None
        offset = point - self.base
        k = self.directions.shape[1]
        if k == 0:
            t = np.zeros(0)
        elif k == 1:
            d = self.directions[:, 0]
            squared = float(d @ d)
            t = np.array([np.clip(offset @ d / squared, 0.0, 1.0) if squared > 0 else 0.0])
        else:
            t = lsq_linear(self.directions, offset, bounds=(0.0, 1.0)).x
        distance = float(np.linalg.norm(offset - self.directions @ t))
        return (distance, self.radius) if distance > self.radius + 1e-9 else None


def line_poses(start: np.ndarray, end: np.ndarray, max_step: float = 0.01,
               max_angle_step: float = math.radians(3)) -> list[np.ndarray]:
    """Poses from ``start`` (excluded) to ``end`` (included) along a straight line, the rotation
    turning uniformly (geodesically) on the way, at most ``max_step`` m / ``max_angle_step`` rad apart."""
    start, end = _check_pose(start, "start"), _check_pose(end, "end")
    rotation = pin.log3(end[:3, :3] @ start[:3, :3].T)
    count = max(1, math.ceil(max(np.linalg.norm(end[:3, 3] - start[:3, 3]) / max_step,
                                 np.linalg.norm(rotation) / max_angle_step)))
    poses = []
    for s in np.linspace(0.0, 1.0, count + 1)[1:]:
        pose = np.eye(4)
        pose[:3, :3] = pin.exp3(s * rotation) @ start[:3, :3]
        pose[:3, 3] = (1 - s) * start[:3, 3] + s * end[:3, 3]
        poses.append(pose)
    return poses


def arc_poses(start: np.ndarray, pivot: Sequence[float], axis: Sequence[float], angle: float,
              max_angle_step: float = math.radians(2)) -> list[np.ndarray]:
    """Poses turning ``start`` rigidly by ``angle`` rad about the line through ``pivot`` along ``axis``
    (right-handed), ``start`` excluded: a handle's path as its door swings on the hinge."""
    start = _check_pose(start, "start")
    pivot_ = np.asarray(pivot, dtype=float)
    axis_ = np.asarray(axis, dtype=float)
    if pivot_.shape != (3,) or axis_.shape != (3,) or np.linalg.norm(axis_) < 1e-9:
        raise ValueError(f"pivot {pivot!r} and axis {axis!r} must be 3-vectors, the axis non-zero")
    axis_ = axis_ / np.linalg.norm(axis_)
    count = max(1, math.ceil(abs(angle) / max_angle_step))
    poses = []
    for s in np.linspace(0.0, 1.0, count + 1)[1:]:
        turn = pin.exp3(s * angle * axis_)
        pose = np.eye(4)
        pose[:3, :3] = turn @ start[:3, :3]
        pose[:3, 3] = pivot_ + turn @ (start[:3, 3] - pivot_)
        poses.append(pose)
    return poses


def _reduced_model(full: pin.Model, joints: Sequence[str], fixed: dict[str, float]) -> pin.Model:
    """The model with every joint but ``joints`` locked (at ``fixed`` or its neutral position)."""
    for name in joints:
        joint = full.joints[full.getJointId(name)]
        if _kind(joint) is None:
            raise ValueError(f"joints: {name!r} is a {joint.shortname()}, not a 1-DoF revolute or prismatic joint "
                             "with limits (continuous joints are not supported)")
    reference = pin.neutral(full)
    for name, value in fixed.items():
        if name not in full.names or name in joints:
            raise ValueError(f"fixed: {name!r} is not an uncontrolled joint of the URDF")
        joint_id = full.getJointId(name)
        if full.joints[joint_id].nq != 1:
            raise ValueError(f"fixed: {name!r} has {full.joints[joint_id].nq} position coordinates, not 1")
        if not math.isfinite(value):
            raise ValueError(f"fixed: {name!r} = {value!r} is not finite")
        reference[full.idx_qs[joint_id]] = value
    bounded = np.isfinite(full.lowerPositionLimit) & np.isfinite(full.upperPositionLimit)
    reference[bounded] = np.clip(reference[bounded], full.lowerPositionLimit[bounded],
                                 full.upperPositionLimit[bounded])
    locked = [j for j in range(1, full.njoints) if full.names[j] not in joints]
    return pin.buildReducedModel(full, locked, reference) if locked else full


def _kind(joint: pin.JointModel) -> str | None:
    """Revolute or prismatic (as "revolute", "prismatic") for a 1-DoF joint, else None."""
    if joint.nq != 1 or joint.nv != 1:
        return None
    name = joint.shortname()
    if name.startswith("JointModelR"):
        return "revolute"
    if name.startswith("JointModelP"):
        return "prismatic"
    return None


def _check_pose(pose: np.ndarray, field: str) -> np.ndarray:
    pose = np.asarray(pose, dtype=float)
    if pose.shape != (4, 4):
        raise ValueError(f"{field}: expected a 4×4 homogeneous matrix, got shape {pose.shape}")
    if not np.all(np.isfinite(pose)):
        raise ValueError(f"{field}: has non-finite entries")
    rotation = pose[:3, :3]
    if not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
        raise ValueError(f"{field}: the upper-left 3×3 block is not a rotation")
    if not np.allclose(pose[3], [0.0, 0.0, 0.0, 1.0]):
        raise ValueError(f"{field}: the last row must be [0, 0, 0, 1], got {pose[3].tolist()}")
    return pose


def _angle_between(a: np.ndarray, b: np.ndarray) -> float:
    return float(math.atan2(np.linalg.norm(np.cross(a, b)), float(a @ b)))


def _rotation_vector(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation (axis × angle) turning unit vector a onto unit vector b."""
    cross = np.cross(a, b)
    sine = float(np.linalg.norm(cross))
    angle = math.atan2(sine, float(a @ b))
    if sine > 1e-12:
        return cross * (angle / sine)
    if angle < 1.0:
        return np.zeros(3)
    other = np.eye(3)[int(np.argmin(np.abs(a)))]  # opposite: turn about any axis perpendicular to a
    perpendicular = np.cross(a, other)
    return perpendicular / np.linalg.norm(perpendicular) * math.pi


def _distance_to_segment(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    direction = end - start
    squared = float(direction @ direction)
    t = float(np.clip((point - start) @ direction / squared, 0.0, 1.0)) if squared > 0 else 0.0
    return float(np.linalg.norm(point - start - t * direction))

