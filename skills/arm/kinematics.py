"""The arm's kinematics with Pinocchio: forward kinematics, Jacobians, the links' skeleton.

The controlled joints (the lift and the arm) form the configuration vector ``q`` in the order the
caller names them; every other joint of the URDF (the fingers, a mobile base) is locked at a fixed
value (`skills.arm.urdf_model.reduced_model`), so one model serves whether the URDF is the bare arm
or the whole robot. Poses are 4×4 homogeneous matrices of the TCP frame in the model's root frame
(the URDF's root link). Inverse kinematics and Cartesian paths are `skills.arm.ik_solver`'s.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pinocchio as pin

from skills.arm.reach import Reach
from skills.arm.urdf_model import reduced_model


class ArmKinematics:
    """Forward kinematics of a serial chain in a URDF, through the chosen joints (its inverse:
    `skills.arm.ik_solver`).

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
        return self.jacobian_and_pose(self.checked_q(q, "q"))[0]

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

    def beyond_reach(self, position: np.ndarray) -> tuple[float, float] | None:
        """How far a TCP position lies from the shoulder, and the reach, when it lies beyond it.

        Args:
            position: (3,) in the root frame.

        Returns:
            (its distance, the reach) in metres, or None within reach.
        """
        return self._reach.excess(position)

    def checked_q(self, q: np.ndarray, field: str) -> np.ndarray:
        """Joint positions as a float array, checked.

        Args:
            q: (dof,) joint positions.
            field: the argument's name, for the error.

        Returns:
            ``q``.

        Raises:
            ValueError: the wrong shape, or a value that is not finite.
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (self.dof,):
            raise ValueError(f"{field}: expected shape ({self.dof},) for joints {list(self.joint_names)}, "
                             f"got {q.shape}")
        if not np.all(np.isfinite(q)):
            raise ValueError(f"{field}: has non-finite values {q.tolist()}")
        return q

    # -- internals --------------------------------------------------------------------------------

    def _model_q(self, q: np.ndarray) -> np.ndarray:
        return self.full_configuration(self.checked_q(q, "q"))
