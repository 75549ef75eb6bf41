"""The arm as its planners know it: kinematics of the TCP and the wrist camera, the joints' limits
and speeds, its ready and stowed poses, and the steps that hold it or re-time a move from where it
really is.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from typing import Any, Self

import numpy as np

from agent.pose import Pose2D
from skills.arm.frames import base_transform
from skills.arm.kinematics import ArmKinematics
from skills.arm.link_shells import link_bulges, link_tubes
from skills.arm.skill_plan import CAREFUL_SPEED, FREE_SPEED, SkillPlanError, Step
from skills.arm.trajectory import JointLimits, plan_trajectory

#: The arm folded up over the base's front edge, the hand 0.35 m ahead of the axis at 1.15 m pointing
#: ahead and 38° down: where skills start from and return to, short of a table's far side and of
#: the drawers and doors that open towards the robot.
READY = (0.1, 0.0, -1.3, 0.0, -2.5, 0.0, 2.1, 0.785)
#: The robot's body around the base's axis (its radius and a margin): no surface reaches in there.
BODY_RADIUS_M = 0.28
#: The gripper's opening between the fingers (m); objects wider than this less a margin are held by their top.
GRIPPER_OPENING_M = 0.08


class ArmModel:
    """One robot's lift and arm: its URDF, its joints and their limits, and the poses it rests in.

    Args:
        urdf_xml: the robot's URDF text.
        joints: in command order, each with ``name``, ``velocity``, ``acceleration`` and ``jerk``
            (the robot description's ``arm.joints``, or `worlds.robot_arm.ArmJoint`).
        tcp_frame: the gripper's TCP frame.
        camera_frame: the wrist camera's optical frame, for camera views (None: no camera).
        dt: the sample period of planned moves (s, in (0, 0.1]).
        ready: where skills start from and return to (clipped into the limits).
        stowed: the arm folded into the base (None: the robot names none).
        gripper_opening: the fingers' opening (m).
        free_speed: free moves' speed, a fraction of the velocity limits.
        careful_speed: the speed of moves near or holding things.
        body_radius: the base's body around its axis (m), over which there is no surface.
        seed: seeds the IK restarts of every plan afresh, so planning is deterministic.

    Raises:
        ValueError: a bad URDF, joint, frame, period or speed.
    """

    def __init__(self, urdf_xml: str, joints: Sequence[Any], tcp_frame: str, camera_frame: str | None = None, *,
                 dt: float = 0.02, ready: Sequence[float] = READY, stowed: Sequence[float] | None = None,
                 gripper_opening: float = GRIPPER_OPENING_M, free_speed: float = FREE_SPEED,
                 careful_speed: float = CAREFUL_SPEED, body_radius: float = BODY_RADIUS_M, seed: int = 0) -> None:
        names = [str(_field(joint, "name")) for joint in joints]
        self.kin = ArmKinematics(urdf_xml, names, tcp_frame)
        self.camera = ArmKinematics(urdf_xml, names, camera_frame) if camera_frame else None
        self.velocity = np.array([float(_field(j, "velocity")) for j in joints])
        self.acceleration = np.array([float(_field(j, "acceleration")) for j in joints])
        self.jerk = np.array([float(_field(j, "jerk")) for j in joints])
        if not (math.isfinite(dt) and 0 < dt <= 0.1):
            raise ValueError(f"dt: {dt!r} must be a number of seconds in (0, 0.1]")
        for name, value in (("free_speed", free_speed), ("careful_speed", careful_speed)):
            if not 0 < value <= 1:
                raise ValueError(f"{name}: {value!r} must lie in (0, 1] (a fraction of the velocity limits)")
        self.dt = dt
        self.ready = self.kin.clip(np.array(ready, dtype=float))
        self.stowed = None if stowed is None else np.array(stowed, dtype=float)
        self.gripper_opening = gripper_opening
        self.free_speed, self.careful_speed = free_speed, careful_speed
        self.seed = seed
        self.body_radius = body_radius
        lifts = [k for k, name in enumerate(names) if "lift" in name]
        #: The lift's index in ``q`` (a prismatic joint raising the whole arm), if the robot has one.
        self.lift_index: int | None = lifts[0] if lifts else None
        #: The first joint of the skeleton kept clear of things: the lift's origin sits in the base.
        self.skeleton_first = 0 if self.lift_index is None else self.lift_index + 1
        #: Each of the skeleton's links as spheres in its own frame (`skills.arm.link_shells`): along
        #: the skeleton, and where it bulges out of the tube round it.
        self.link_tubes = link_tubes(self.kin, self.skeleton_first)
        self.link_bulges = link_bulges(urdf_xml, self.kin, self.skeleton_first)

    @classmethod
    def from_description(cls, description: Mapping[str, Any], **options: Any) -> Self:
        """The arm of the robot a world describes, so that planning needs nothing but the world's word.

        Args:
            description: ``world/robot/description``'s reply (``urdf``, ``arm`` with ``joints``,
                ``tcp_frame`` and optionally ``stowed``, ``finger_travel``, ``wrist_camera_frame``;
                ``robot.radius``).
            **options: keyword arguments of the constructor, overriding what the description says.

        Returns:
            An instance of ``cls`` for that robot.

        Raises:
            ValueError: the description lacks the URDF or the arm's joints or TCP frame.
        """
        try:
            arm = description["arm"]
            urdf = description["urdf"]
            joints, tcp = arm["joints"], arm["tcp_frame"]
        except (KeyError, TypeError) as error:
            raise ValueError(f"robot description: missing {error} (need urdf and arm.joints/tcp_frame)") from None
        options.setdefault("stowed", arm.get("stowed"))
        if "finger_travel" in arm:
            options.setdefault("gripper_opening", 2 * float(arm["finger_travel"]))
        robot = description.get("robot")
        if isinstance(robot, Mapping) and "radius" in robot:
            options.setdefault("body_radius", float(robot["radius"]) + 0.03)
        return cls(urdf, joints, tcp, arm.get("wrist_camera_frame"), **options)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """The lift's and arm's joints, in command order."""
        return self.kin.joint_names

    def limits(self, speed: float) -> JointLimits:
        """The limits a move is timed under.

        Args:
            speed: a fraction of the velocity limits.

        Returns:
            The scaled velocity limits with the full acceleration and jerk limits.
        """
        return JointLimits(self.velocity * speed, self.acceleration, self.jerk)

    def start_configuration(self, q: np.ndarray) -> np.ndarray:
        """Where a plan starts: the arm's joint positions as it reports them, checked and clipped.

        Args:
            q: the arm's joint positions.

        Returns:
            The positions clipped into the limits.

        Raises:
            SkillPlanError: not ``dof`` finite numbers.
        """
        q = np.asarray(q, dtype=float)
        if q.shape != (self.kin.dof,) or not np.all(np.isfinite(q)):
            raise SkillPlanError(f"start: joint positions {np.round(q, 4).tolist()} are not {self.kin.dof} "
                                 "finite numbers")
        return self.kin.clip(q)

    def samples(self, waypoints: np.ndarray, speed: float, pass_through: bool = True) -> np.ndarray:
        """The joint samples of a move, every ``dt`` after its start, for the world's trajectory command.

        Args:
            waypoints: (n, dof) joint waypoints within the limits, the first where the arm is.
            speed: a fraction of the velocity limits.
            pass_through: pass intermediate waypoints at speed (`skills.arm.trajectory`); False:
                stop at each, so the arm keeps to the straight joint-space lines between them.

        Returns:
            The jerk-limited trajectory's samples, the start left out (unless it is the only one),
            clipped into the limits (Ruckig may overshoot a waypoint on a limit by 1e-16).

        Raises:
            ValueError: malformed waypoints.
            RuntimeError: Ruckig finds no trajectory.
        """
        trajectory = plan_trajectory(waypoints, self.limits(speed), self.dt, pass_through)
        samples = trajectory.positions[1:] if len(trajectory.positions) > 1 else trajectory.positions
        return self.kin.clip(samples)

    def base_pose_from(self, q: np.ndarray, tcp_world: np.ndarray) -> Pose2D:
        """Where the base stands, read off an arm state, so planning needs no separate base pose.

        Args:
            q: the joint positions.
            tcp_world: the TCP's 4×4 world pose at ``q``.

        Returns:
            The base pose: the TCP's world pose times the inverse of its forward kinematics.

        Raises:
            ValueError: the implied base is off the floor or tilted (the pose does not match the joints).
        """
        base = np.asarray(tcp_world, dtype=float) @ np.linalg.inv(self.kin.forward(q))
        if abs(base[2, 3]) > 0.02 or abs(base[2, 2] - 1.0) > 1e-3:
            raise ValueError(f"arm state: the TCP pose puts the base at z {base[2, 3]:.3f} m, tilted "
                             f"{math.degrees(math.acos(min(1.0, base[2, 2]))):.1f}°: it does not match the joints")
        return Pose2D(float(base[0, 3]), float(base[1, 3]), math.atan2(base[1, 0], base[0, 0]))

    def tcp_world(self, q: np.ndarray, base_pose: Pose2D) -> np.ndarray:
        """Where the TCP is in the world.

        Args:
            q: the joint positions.
            base_pose: where the base stands.

        Returns:
            The TCP's 4×4 world pose.
        """
        return base_transform(base_pose) @ self.kin.forward(q)

    def retime(self, step: Step, q: np.ndarray) -> Step:
        """A move again from where the arm really is (a touch or a contact stopped it short).

        Args:
            step: a planned step.
            q: where the arm is.

        Returns:
            A move from ``q`` through ``step``'s other waypoints at its speed; a gripper step as it is.

        Raises:
            ValueError: malformed positions.
            RuntimeError: Ruckig finds no trajectory.
        """
        if step.kind != "move" or step.waypoints is None:
            return step
        waypoints = np.vstack([np.asarray(q, dtype=float)[None, :], step.waypoints[1:]])
        waypoints = self.kin.clip(waypoints)
        return replace(step, samples=self.samples(waypoints, step.speed), dt=self.dt, waypoints=waypoints)

    def hold(self, q: np.ndarray, duration_s: float = 0.0) -> Step:
        """A move that holds the arm where it is (after a motion that fell short, or to let what
        it moved come to rest).

        Args:
            q: where the arm is.
            duration_s: how long to hold it there; at least one sample.

        Returns:
            The move, at the careful speed.
        """
        q = self.kin.clip(np.asarray(q, dtype=float))
        count = max(1, math.ceil(duration_s / self.dt - 1e-9))
        return Step("move", "hold", np.repeat(q[None, :], count, axis=0), self.dt, q[None, :], self.careful_speed)


def _field(entry: Any, name: str) -> Any:
    return entry[name] if isinstance(entry, Mapping) else getattr(entry, name)
