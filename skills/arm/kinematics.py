"""The arm's kinematics: forward kinematics, Jacobians, inverse kinematics and Cartesian paths
with Pinocchio.

The controlled joints (the lift and the arm) form the configuration vector ``q`` in the order the
caller names them; every other joint of the URDF (the fingers, a mobile base) is locked at a fixed
value (`skills.arm.urdf_model.reduced_model`), so one model serves whether the URDF is the bare arm
or the whole robot. Poses are 4×4 homogeneous matrices of the TCP frame in the model's root frame
(the URDF's root link).

IK runs damped least-squares descents (`skills.arm.ik_descent.IKDescent`); a run that stalls
restarts from a random configuration drawn from a seeded generator, so a solve is reproducible.
Targets beyond the arm's reach (`skills.arm.reach.Reach`) fail at once. Cartesian paths (along
`skills.arm.tcp_paths`) chain IK solutions, each seeded from the previous one, and fail clearly
when a waypoint is unreachable or the arm would have to jump between consecutive waypoints.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from skills.arm.frames import check_pose
from skills.arm.ik_descent import IK_MODES, IKDescent, IKMode
from skills.arm.reach import Reach
from skills.arm.urdf_model import reduced_model


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


class ArmKinematics:
    """Forward and inverse kinematics of a serial chain in a URDF, through the chosen joints.

    Args:
        urdf_xml: the URDF's text.
        joints: the controlled joints (1-DoF revolute or prismatic, with finite limits), in the
            order of ``q``.
        tcp_frame: the link or frame whose pose is controlled.
        fixed: positions for other 1-DoF joints, which otherwise sit at their neutral position
            (zero, clipped into their limits).

    Raises:
        ValueError: a joint or the frame is unknown, a joint repeats, is of an unsupported kind or
            lacks finite limits.
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
        self.model = reduced_model(full, self.joint_names, dict(fixed or {}))
        self.data = self.model.createData()
        self._frame = self.model.getFrameId(tcp_frame)
        self._joint_ids = [self.model.getJointId(n) for n in self.joint_names]
        self._q_index = np.array([self.model.idx_qs[j] for j in self._joint_ids])
        self._v_index = np.array([self.model.idx_vs[j] for j in self._joint_ids])
        self._qm = pin.neutral(self.model)
        self.lower = self.model.lowerPositionLimit[self._q_index].copy()
        self.upper = self.model.upperPositionLimit[self._q_index].copy()
        self.velocity_limits = self.model.velocityLimit[self._v_index].copy()
        for name, lo, hi in zip(self.joint_names, self.lower, self.upper, strict=True):
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
                raise ValueError(f"joints: {name!r} needs finite limits with lower ≤ upper, got [{lo}, {hi}]")
        self._reach = Reach.of(self.model, self._frame, self.joint_names, self.lower, self.upper,
                               self.full_configuration)
        self._lines: dict[int, tuple[tuple[str, np.ndarray], ...]] = {}

    @property
    def dof(self) -> int:
        """The number of controlled joints."""
        return len(self.joint_names)

    @property
    def reach(self) -> float:
        """An upper bound on the TCP's distance from the shoulder (the first revolute joint)."""
        return self._reach.radius

    def home(self) -> np.ndarray:
        """A neutral IK seed far from all limits.

        Returns:
            The middle of every joint's range.
        """
        return 0.5 * (self.lower + self.upper)

    def random_configuration(self, rng: np.random.Generator) -> np.ndarray:
        """A restart for IK.

        Args:
            rng: the generator drawn from.

        Returns:
            Joint positions drawn uniformly within the limits.
        """
        return rng.uniform(self.lower, self.upper)

    def clip(self, q: np.ndarray) -> np.ndarray:
        """Joint positions brought within the limits.

        Args:
            q: (dof,) joint positions, or (n, dof) rows of them.

        Returns:
            A clipped copy.
        """
        return np.clip(q, self.lower, self.upper)

    def within_limits(self, q: np.ndarray, tolerance: float = 1e-9) -> bool:
        """Whether joint positions lie within the limits.

        Args:
            q: (dof,) joint positions.
            tolerance: how far past a limit still counts as within it.

        Returns:
            True when every joint is within its limits.
        """
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= self.lower - tolerance) and np.all(q <= self.upper + tolerance))

    def forward(self, q: np.ndarray) -> np.ndarray:
        """Where the TCP is.

        Args:
            q: (dof,) joint positions.

        Returns:
            The 4×4 pose of the TCP in the root frame.
        """
        pin.framesForwardKinematics(self.model, self.data, self._model_q(q))
        return self.data.oMf[self._frame].homogeneous.copy()

    def link_lines(self, first: int = 0) -> tuple[tuple[str, np.ndarray], ...]:
        """The arm's skeleton link by link, each in its own frame: for each controlled joint from the
        ``first`` on but the last, the joint's name and the polyline its link runs along, from the
        joint's origin to the next joint's, by way of the corner where the link turns when the next
        joint sits both aside of this one's axis and along it (its placement's x, then the rest, as
        the URDF's modified Denavit–Hartenberg offsets run). The Panda's forearm runs 8 cm aside of
        the elbow, then 38 cm along to the wrist: a straight line between the two origins passes up
        to 8 cm inside the link's shell, where the elbow's side of the forearm is.

        Args:
            first: the first joint (in the order of ``joints``) the skeleton starts at.

        Returns:
            (joint name, (k, 3) points in that joint's frame), in order along the chain; worked out
            once per ``first`` (the clearance checks ask at every posture), read-only.
        """
        if first not in self._lines:
            lines = []
            for name, child in zip(self.joint_names[first:-1], self._joint_ids[first + 1:], strict=True):
                offset = self.model.jointPlacements[child].translation.copy()
                turns = abs(offset[0]) > 1e-6 and np.linalg.norm(offset[1:]) > 1e-6
                corner = [np.array([offset[0], 0.0, 0.0])] if turns else []
                line = np.array([np.zeros(3), *corner, offset])
                line.flags.writeable = False
                lines.append((name, line))
            self._lines[first] = tuple(lines)
        return self._lines[first]

    def link_frames(self, q: np.ndarray, first: int = 0) -> np.ndarray:
        """Where the controlled joints' frames are, from the ``first`` on.

        Args:
            q: (dof,) joint positions.
            first: the first joint (in the order of ``joints``).

        Returns:
            (k, 4, 4) poses in the root frame, in order along the chain.
        """
        pin.forwardKinematics(self.model, self.data, self._model_q(q))
        return np.array([self.data.oMi[joint].homogeneous for joint in self._joint_ids[first:]])

    def skeleton(self, q: np.ndarray, first: int = 0) -> np.ndarray:
        """The arm's skeleton, for clearance checks: `link_lines` where the joints are.

        Args:
            q: (dof,) joint positions.
            first: the first joint (in the order of ``joints``) the skeleton starts at.

        Returns:
            (k, 3) points in the root frame, in order along the chain: the joints' origins and the
            corners between them.
        """
        frames = self.link_frames(q, first)
        points = [frames[0][:3, 3][None, :]]
        for frame, (_, line) in zip(frames, self.link_lines(first)):
            points.append(line[1:] @ frame[:3, :3].T + frame[:3, 3])
        return np.vstack(points)

    def jacobian(self, q: np.ndarray) -> np.ndarray:
        """How the TCP moves with the joints.

        Args:
            q: (dof,) joint positions.

        Returns:
            The 6×dof Jacobian of the TCP: rows (linear velocity of its origin, angular velocity),
            both in root-frame axes; columns in the order of ``joints``.
        """
        return self.jacobian_and_pose(self._check_q(q, "q"))[0]

    def full_configuration(self, q: np.ndarray) -> np.ndarray:
        """The model's configuration vector for controlled joint positions (not checked).

        Args:
            q: (dof,) joint positions.

        Returns:
            The reduced model's configuration, the uncontrolled coordinates at their neutral values.
        """
        qm = self._qm.copy()
        qm[self._q_index] = q
        return qm

    def jacobian_and_pose(self, q: np.ndarray) -> tuple[np.ndarray, pin.SE3]:
        """The Jacobian (as `jacobian`) and the TCP pose in one kinematics pass, for IK's inner loop.

        Args:
            q: (dof,) joint positions, not checked.

        Returns:
            (the 6×dof world-aligned Jacobian, the TCP pose, a view into the model data that the
            next kinematics call overwrites).
        """
        full = pin.computeFrameJacobian(self.model, self.data, self.full_configuration(q), self._frame,
                                        pin.LOCAL_WORLD_ALIGNED)
        return full[:, self._v_index], self.data.oMf[self._frame]

    def solve_ik(self, target_pose: np.ndarray, q_seed: np.ndarray | None = None,
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
            target_pose: the TCP's 4×4 target in the root frame.
            q_seed: where the first run starts (default: `home`).
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
        seed = self.home() if q_seed is None else self._check_q(q_seed, "q_seed")
        rng = np.random.default_rng(0) if rng is None else rng

        too_far = self._reach.excess(target[:3, 3])
        if too_far is not None:
            distance, radius = too_far
            q = self.clip(seed)
            position_error, orientation_error = self._errors(q, target, mode, axis / np.linalg.norm(axis))
            return IKResult(False, q, position_error, orientation_error, 0, 0,
                            f"target {distance:.2f} m from the shoulder, beyond the arm's {radius:.2f} m reach")

        descent = IKDescent(self.jacobian_and_pose, self.lower, self.upper, target, mode, axis / np.linalg.norm(axis),
                            position_weight, orientation_weight, position_tolerance, orientation_tolerance, damping,
                            max_step)
        best: tuple[float, np.ndarray, float, float] | None = None
        iterations = 0
        for run in range(max_restarts + 1):
            start = self.clip(seed) if run == 0 else self.random_configuration(rng)
            converged, q, used = descent.run(start, max_iterations)
            iterations += used
            position_error, orientation_error = self._errors(q, target, mode, descent.axis)
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

    def plan_cartesian_path(self, start_q: np.ndarray, poses: Sequence[np.ndarray], *, mode: IKMode = "pose",
                            max_joint_jump: float | Sequence[float] = 0.3, max_deviation: float = 0.002,
                            **ik_options: object) -> CartesianPath:
        """Joint waypoints that take the TCP through ``poses`` in turn.

        Each pose is solved from the previous solution without random restarts (a restart would
        land on another arm posture), so the arm moves continuously.

        Args:
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
            pose = check_pose(pose, f"poses[{index}]")
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
        return self.full_configuration(self._check_q(q, "q"))

    def _errors(self, q: np.ndarray, target: np.ndarray, mode: IKMode, axis: np.ndarray) -> tuple[float, float]:
        pose = self.forward(q)
        position_error = float(np.linalg.norm(target[:3, 3] - pose[:3, 3]))
        if mode == "axis":
            return position_error, _angle_between(pose[:3, :3] @ axis, target[:3, :3] @ axis)
        return position_error, float(np.linalg.norm(pin.log3(target[:3, :3] @ pose[:3, :3].T)))


def _angle_between(a: np.ndarray, b: np.ndarray) -> float:
    return float(math.atan2(np.linalg.norm(np.cross(a, b)), float(a @ b)))


def _distance_to_segment(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    direction = end - start
    squared = float(direction @ direction)
    t = float(np.clip((point - start) @ direction / squared, 0.0, 1.0)) if squared > 0 else 0.0
    return float(np.linalg.norm(point - start - t * direction))
