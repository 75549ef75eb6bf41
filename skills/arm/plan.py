"""Motion plans for the arm primitives: from where the arm is to the steps the world will run.

Pure planning (Pinocchio IK from `skills.arm.kinematics`, Ruckig trajectories from `skills.arm.trajectory`),
no py_trees and no bus: given the arm's joint positions, the base's pose and a target perceived in
the world frame, each ``plan_*`` method returns a `SkillPlan`, a list of `Step`:

- ``move``: joint samples (N, dof) every ``dt`` seconds for the world's ``arm_trajectory`` command,
  with the joint waypoints they pass through (so an executor can re-time the rest of a motion from
  wherever the arm really stopped) and what to check when it ends;
- ``gripper``: ``open`` or ``close``, and for a close what must then be held (a handle, an object).

Frames. Targets come in the world frame (z up); the kinematics work in the robot's root frame (the
URDF's ``base_link``: the floor under the base's axis, x ahead), so every pose is taken into it
with the base pose (x, y, yaw). The base pose itself is read off an arm state: the TCP's world pose
times the inverse of its forward kinematics (`ArmPlanner.base_pose_from`).

The primitives (RoboEXP's seven, §2 of the spec):

- open / close a door or drawer (`ArmPlanner.plan_open`, `ArmPlanner.plan_close`): a free move to a
  staging pose, a straight line out to the pre-grasp pose `APPROACH_M` out along the gripper's
  axis and in onto the handle, close, follow the part's path (a line for drawers, an arc about the
  hinge for doors, the TCP turning with the door), open, back out along the gripper's axis and
  withdraw straight towards the base (`WITHDRAW_AHEAD_M`; the staging pose is the same withdrawal
  ahead of the pre-grasp, so closing starts where opening ended). The chain is solved from the
  closed grasp outwards whichever way the part moves, so a close takes the posture its open took.
  Grasp variants (the hand turned half a turn about its axis, tilted about the bar:
  `skills.arm.grasps.level_grasps`) and the grasp's IK postures (structured seeds, then a few random restarts) are tried in
  turn until one chain is reachable throughout. With ``surface_z`` (a table's top) variants whose
  hand would come down onto it are refused (`skills.arm.grasps.HAND_BOXES`): a bar less than ~9 cm above the table
  cannot be grasped by a Panda hand 21 cm tall across its fingers. A drawer's bar is then
  grasped from above, the fingers closed and their tips brought down onto it until they touch
  (`skills.arm.grasps.handle_top_grasps`). An opening may end holding the handle (``hold``);
  `ArmPlanner.plan_close_held` then pushes the part shut from that grasp;
- pick an object away / back (`ArmPlanner.plan_pick`): top-down. Above the object, down onto its
  top (the fingers closing across the line of sight from the robot where the object fits that way,
  since perception places things worst along it; an object wider than the opening is held by the
  closed fingertips brought down onto its top until they touch, `skills.arm.grasps.object_grasps`),
  close, lift, carry at height, lower until the object stands a little above where it should (the
  world puts a released object down onto whatever is under it), open, back up, ready (`READY`);
- move the wrist camera (`ArmPlanner.plan_look`): one free move that puts the wrist camera's
  optical frame at a standoff from a point, its optical axis on the point (IK "axis" mode: the
  rotation about the axis is free), trying steeper and shallower views and shorter and longer
  standoffs until one is reachable.

Free moves are joint-space; with a ``surface_z`` the hand is kept above it over the whole move
(`_Builder.free_move`: else with the lift raised on the way, else a planning error). Beyond that
nothing here checks collisions: the world reports contacts, and free moves and approaches stop on
the first one.

Failures raise `SkillPlanError` naming the stage and the target: ``IK: grasp pose of drawer handle
unreachable: ...``, ``clearance: the hand at the drawer handle (0.822 m high) would come ...``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from agent.perception.grasp_poses import grasp_pose
from agent.perception.part_geometry import PartGeometry
from agent.perception.part_motion import moved_geometry
from skills.arm.grasps import (
    LIFT_OFF_M,
    TOUCH_SEARCH_M,
    UP,
    HandleGrasp,
    ObjectGrasp,
    front_clearance,
    hand_bottom,
    handle_top_grasps,
    level_grasps,
    local_pose,
    object_grasps,
)
from skills.arm.kinematics import ArmKinematics, IKMode, line_poses
from skills.arm.trajectory import JointLimits, plan_trajectory

#: The arm folded up over the base's front edge, the hand 0.35 m ahead of the axis at 1.15 m pointing
#: ahead and 38° down: where skills start from and return to, short of a table's far side and of
#: the drawers and doors that open towards the robot.
READY = (0.1, 0.0, -1.3, 0.0, -2.5, 0.0, 2.1, 0.785)
#: IK seeds reaching ahead with the hand level: fingers above each other (a level bar) or side by side.
_AHEAD = ((0.2, 0.0, 0.0, 0.0, -2.0, 0.0, 3.57, -0.785), (0.2, 0.0, 0.0, 0.0, -2.0, 0.0, 3.57, 0.785))
#: How far out along the gripper's axis a grasp is approached from and retreated to.
APPROACH_M = 0.10
#: A part skill ends with the hand drawn straight back towards the base until it is this far ahead
#: of the base's axis (at the height and on the side it let go), clear of what it opened.
WITHDRAW_AHEAD_M = 0.35
#: Cartesian step of approaches, pulls and carries (m), and of door arcs (rad).
LINE_STEP_M = 0.01
ARC_STEP_RAD = math.radians(1.5)
#: The robot's body around the base's axis (its radius and a margin): no surface reaches in there.
BODY_RADIUS_M = 0.28
#: How far above ``surface_z`` the hand keeps.
SURFACE_CLEARANCE_M = 0.01
#: Random IK restarts tried for a handle's grasp, per grasp variant, after the structured seeds.
PART_RESTARTS = 4
#: A part's path solved anew is the one the arm holding it is on when it passes within this (rad or
#: m, any joint) of where the arm is.
HELD_MATCH_RAD = 0.05
#: The gripper's opening between the fingers (m); objects wider than this less a margin are held by their top.
GRIPPER_OPENING_M = 0.08
#: How far (m) open fingers must clear an object on either side to close around it; else they rest
#: on its top. The memory places things to within its 1 cm voxels: a 7 cm carton in the 8 cm
#: opening, 5 mm either side, was missed by a finger landing on its top.
STRADDLE_CLEARANCE_M = 0.008
#: Speeds as fractions of the joints' velocity limits: free moves, and moves near or holding things.
FREE_SPEED, CAREFUL_SPEED = 0.5, 0.25
#: Wrist-camera views tried: (degrees below the horizontal, standoff m), best first.
LOOK_VIEWS = tuple((pitch, d) for d in (0.3, 0.4, 0.25, 0.5) for pitch in (60.0, 45.0, 75.0, 90.0, 30.0))
#: How far a free move tries raising the lift to swing the arm over a surface, least first (m).
LIFT_RISES_M = (0.15, 0.3, 0.45)
#: An arm within this (rad or m, any joint) of its stowed or ready pose folds without backing off first.
FOLDED_RAD = 0.1


class SkillPlanError(RuntimeError):
    """No plan: the text names the stage and the target, e.g. ``IK: grasp pose of drawer handle
    unreachable: target 1.02 m from the shoulder, beyond the arm's 0.95 m reach``."""


@dataclass(frozen=True, eq=False)
class PartMotion:
    """What a move holding a handle should do to its part: take its opening from ``start`` to ``end``
    (m for drawers, rad for doors, 0 = closed). ``reference`` is the TCP's world position when it
    grasps the closed part; `opening` measures the part's opening from where the TCP is."""

    geometry: PartGeometry  # the part as seen closed
    reference: np.ndarray
    start: float
    end: float

    def opening(self, tcp_point: np.ndarray) -> float:
        """The part's opening implied by the TCP (which holds the handle) standing at ``tcp_point``."""
        g = self.geometry
        point = np.asarray(tcp_point, dtype=float)
        if g.kind == "drawer":
            return float((point - self.reference) @ g.normal)
        assert g.hinge_point is not None and g.hinge_axis is not None
        axis = g.hinge_axis
        a = self.reference - g.hinge_point
        b = point - g.hinge_point
        a, b = a - (a @ axis) * axis, b - (b @ axis) * axis
        return float(math.atan2(np.cross(a, b) @ axis, a @ b))

    @property
    def unit(self) -> str:
        return "m" if self.geometry.kind == "drawer" else "rad"


@dataclass(frozen=True, eq=False)
class Step:
    """One command of a plan. ``kind`` "move": ``samples`` (N, dof) every ``dt`` s through the joint
    ``waypoints`` at ``speed`` (a fraction of the velocity limits), ending with the TCP at
    ``tcp_target`` (world); ``part_motion`` when it moves a held part; ``touch`` ("handle" or
    "object") when it is a touch grasp's approach, which arrives when it stops on touching that.
    ``kind`` "gripper": ``action`` "open" or "close" and, closing, ``expect_held`` ("handle" or
    "object"; None: the fingers close on nothing, to touch with their tips)."""

    kind: str
    name: str
    samples: np.ndarray | None = None
    dt: float = 0.0
    waypoints: np.ndarray | None = None
    speed: float = FREE_SPEED
    stop_on_contact: bool = False
    tcp_target: np.ndarray | None = None
    part_motion: PartMotion | None = None
    action: str | None = None
    expect_held: str | None = None
    touch: str | None = None

    @property
    def duration_s(self) -> float:
        return 0.0 if self.samples is None else len(self.samples) * self.dt

    def describe(self) -> str:
        if self.kind == "gripper":
            return f"{self.name}: gripper {self.action}"
        assert self.samples is not None
        return f"{self.name}: {len(self.samples)} samples, {self.duration_s:.2f} s"


@dataclass(frozen=True, eq=False)
class SkillPlan:
    """The steps of one primitive and what planning them cost.

    ``ik_ms``/``ik_solves``: IK time and calls, over every grasp variant tried; ``trajectory_ms``:
    Ruckig time; ``planning_ms``: all of it. ``info`` carries what the skill reports afterwards
    (the grasp pose, the camera pose, the place point...), world frame.
    """

    skill: str
    steps: tuple[Step, ...]
    base_pose: tuple[float, float, float]
    start_q: np.ndarray
    final_q: np.ndarray
    ik_ms: float
    ik_solves: int
    trajectory_ms: float
    planning_ms: float
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def duration_s(self) -> float:
        """The motions' total duration (gripper actions not counted)."""
        return sum(step.duration_s for step in self.steps)

    def describe(self) -> str:
        grasp = f" ({self.info['grasp']} grasp)" if "grasp" in self.info else ""
        lines = [f"{self.skill}{grasp}: {len(self.steps)} steps, {self.duration_s:.1f} s of motion, planned in "
                 f"{self.planning_ms:.0f} ms ({self.ik_solves} IK solves {self.ik_ms:.0f} ms, "
                 f"trajectories {self.trajectory_ms:.0f} ms)"]
        lines += [f"  {step.describe()}" for step in self.steps]
        return "\n".join(lines)


def base_transform(base_pose: Sequence[float]) -> np.ndarray:
    """The 4x4 world pose of ``base_link`` standing at (x, y, yaw)."""
    x, y, yaw = (float(v) for v in base_pose)
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s, 0.0, x], [s, c, 0.0, y], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]])


def _field(entry: Any, name: str) -> Any:
    return entry[name] if isinstance(entry, Mapping) else getattr(entry, name)


class ArmPlanner:
    """Plans the primitives for one robot: its URDF, its lift-and-arm joints and their limits.

    ``joints``: in command order, each with ``name``, ``velocity``, ``acceleration`` and ``jerk``
    (the robot description's ``arm.joints``, or `worlds.robot_arm.ArmJoint`). ``camera_frame``: the
    wrist camera's optical frame, for `plan_look`. Planning is deterministic: IK restarts draw from
    a generator seeded with ``seed`` afresh for every plan.
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

    @classmethod
    def from_description(cls, description: Mapping[str, Any], **options: Any) -> ArmPlanner:
        """The planner for the robot a world describes (``world/robot/description``'s reply)."""
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
        return self.kin.joint_names

    def limits(self, speed: float) -> JointLimits:
        return JointLimits(self.velocity * speed, self.acceleration, self.jerk)

    def base_pose_from(self, q: np.ndarray, tcp_world: np.ndarray) -> tuple[float, float, float]:
        """Where the base stands, from the joints and the TCP's world pose (an arm state's)."""
        base = np.asarray(tcp_world, dtype=float) @ np.linalg.inv(self.kin.forward(q))
        if abs(base[2, 3]) > 0.02 or abs(base[2, 2] - 1.0) > 1e-3:
            raise ValueError(f"arm state: the TCP pose puts the base at z {base[2, 3]:.3f} m, tilted "
                             f"{math.degrees(math.acos(min(1.0, base[2, 2]))):.1f}°: it does not match the joints")
        return float(base[0, 3]), float(base[1, 3]), math.atan2(base[1, 0], base[0, 0])

    def tcp_world(self, q: np.ndarray, base_pose: Sequence[float]) -> np.ndarray:
        return base_transform(base_pose) @ self.kin.forward(q)

    def retime(self, step: Step, q: np.ndarray) -> Step:
        """``step`` again, starting from ``q`` (where the arm really is) through its other waypoints."""
        if step.kind != "move" or step.waypoints is None:
            return step
        waypoints = np.vstack([np.asarray(q, dtype=float)[None, :], step.waypoints[1:]])
        waypoints = self.kin.clip(waypoints)
        trajectory = plan_trajectory(waypoints, self.limits(step.speed), self.dt)
        samples = trajectory.positions[1:] if len(trajectory.positions) > 1 else trajectory.positions
        return replace(step, samples=self.kin.clip(samples), dt=self.dt, waypoints=waypoints)

    def hold(self, q: np.ndarray) -> Step:
        """A one-sample move that holds the arm where it is (after a motion that fell short)."""
        q = self.kin.clip(np.asarray(q, dtype=float))
        return Step("move", "hold", q[None, :], self.dt, q[None, :], self.careful_speed)

    # -- the primitives ----------------------------------------------------------------------------

    def plan_open(self, q: np.ndarray, base_pose: Sequence[float], geometry: PartGeometry, amount: float, *,
                  surface_z: float | None = None, skill: str | None = None, hold: bool = False) -> SkillPlan:
        """Open the part ``geometry`` (as seen closed) by ``amount`` (m for drawers, rad for doors).

        ``surface_z``: the top of what the furniture stands on (a table); the hand keeps above it.
        With ``hold`` the plan ends holding the handle, the part pulled open (no letting go, no
        backing off): it cannot swing on or be knocked while the robot looks, and
        `plan_close_held` shuts it again without a second grasp.
        """
        _check_amount(geometry, amount)
        return self._part(q, base_pose, geometry, 0.0, float(amount), skill or f"open_{geometry.kind}", surface_z,
                          hold)

    def plan_close_held(self, q: np.ndarray, base_pose: Sequence[float], geometry: PartGeometry, amount: float, *,
                        surface_z: float | None = None, skill: str | None = None) -> SkillPlan:
        """Shut a part that stands open by ``amount`` with the hand on its handle (``geometry`` as
        seen closed): the hand rides the handle back along the part's path from the grasp it has
        now (whichever variant the opening took, read off ``q``), lets go and backs off as
        `plan_close` would. ``surface_z`` as for `plan_open`."""
        _check_amount(geometry, amount)
        what = f"{geometry.kind} handle"
        builder = _Builder(self, q, base_pose, surface_z)
        grasp = builder.base @ self.kin.forward(builder.q)
        held = np.linalg.inv(grasp_pose(moved_geometry(geometry, amount))) @ grasp
        step = LINE_STEP_M if geometry.kind == "drawer" else ARC_STEP_RAD
        values = np.linspace(0.0, float(amount), max(1, math.ceil(amount / step - 1e-9)) + 1)
        poses = [grasp_pose(moved_geometry(geometry, float(v))) @ held for v in values]
        try:
            swept = builder.path(builder.q, poses[::-1][1:], f"closing path of {what}")
        except SkillPlanError as error:
            swept = self._retraced(builder, poses, what, error)
        retreat = self._off(builder, swept[-1], poses[0], f"retreat from {what}")
        builder.move(f"push the {geometry.kind} closed", swept, careful=True, tcp_target=poses[0],
                     part_motion=PartMotion(geometry, poses[0][:3, 3], float(amount), 0.0))
        builder.let_go(what, retreat)
        info = {"grasp_pose": grasp, "release_pose": poses[0], "kind": geometry.kind, "start": float(amount),
                "end": 0.0, "held": True}
        return builder.finish(skill or f"close_{geometry.kind}", info)

    def _retraced(self, builder: _Builder, poses: list[np.ndarray], what: str, error: SkillPlanError) -> np.ndarray:
        """The joint path of ``poses`` (closed to open) solved outwards from the closed grasp as an
        opening solves it, reversed: IK tracked backwards from the open end of a redundant arm
        drifts and may jump where the opening's own path did not. Taken only when it ends (at the
        open end) where the arm is; else ``error``."""
        for closed in builder.solutions(poses[0], f"grasp pose of {what}", restarts=PART_RESTARTS):
            try:
                out = builder.path(closed, poses[1:], f"opening path of {what}")
            except SkillPlanError:
                continue
            if np.abs(out[-1] - builder.q).max() < HELD_MATCH_RAD:
                return out[::-1]
        raise error

    def plan_close(self, q: np.ndarray, base_pose: Sequence[float], geometry: PartGeometry, amount: float, *,
                   geometry_is_open: bool = False, surface_z: float | None = None,
                   skill: str | None = None) -> SkillPlan:
        """Close a part that stands open by ``amount``. ``geometry`` is the part as seen closed (what
        its opening used), or with ``geometry_is_open`` as seen now, open. ``surface_z`` as for `plan_open`."""
        _check_amount(geometry, amount)
        if geometry_is_open:
            geometry = moved_geometry(geometry, -float(amount))
        return self._part(q, base_pose, geometry, float(amount), 0.0, skill or f"close_{geometry.kind}", surface_z)

    def plan_pick(self, q: np.ndarray, base_pose: Sequence[float], object_point: Sequence[float],
                  extent: Sequence[float], place_point: Sequence[float], *, skill: str = "pick_away",
                  surface_z: float | None = None, lift_m: float = 0.15, clearance_m: float = 0.015,
                  grasp_depth_m: float | None = None) -> SkillPlan:
        """Pick the object whose top grasp point is ``object_point`` (world) and whose box is ``extent``
        (dx, dy, dz), and put it down so that that point ends ``clearance_m`` above ``place_point``.
        The fingers close around it where it fits between them, else their tips come down on its
        top (`skills.arm.grasps.object_grasps`); ``info["grasp"]`` says which.
        ``surface_z``: the table's top, which free moves keep the hand above."""
        top = _vector(object_point, "object_point")
        place = _vector(place_point, "place_point")
        size = _vector(extent, "extent")
        if np.any(size <= 0):
            raise SkillPlanError(f"pick: extent {np.round(size, 3).tolist()} must be positive")
        depth = grasp_depth_m if grasp_depth_m is not None else min(0.025, max(0.005, size[2] / 2 - 0.005))
        builder = _Builder(self, q, base_pose, surface_z)
        failures: list[str] = []
        for way in object_grasps(size, top, base_pose, self.gripper_opening - 2 * STRADDLE_CLEARANCE_M, depth):
            grasp = _pose(way.rotation, top - way.depth * UP)
            release = _pose(way.rotation, place + (clearance_m - way.depth) * UP)
            above_grasp, above_release = _shifted(grasp, lift_m * UP), _shifted(release, lift_m * UP)
            down = "down onto the object's top" if way.touch else "down onto the object"
            try:
                chain = builder.try_chain([
                    ("above the object", "free", above_grasp),
                    (down, "line", grasp),
                    ("lift", "line", above_grasp),
                    ("carry", "line", above_release),
                    ("lower", "line", release),
                    ("back up", "line", above_release),
                ])
                descent = self._searched(builder, chain[1], grasp, down) if way.touch else chain[1]
            except SkillPlanError as error:
                failures.append(str(error))
                continue
            builder.free_move("to above the object", chain[0][-1])
            self._grasp(builder, way, down, descent, grasp, "object")
            builder.move("lift", chain[2], careful=True, tcp_target=above_grasp)
            builder.move("carry", chain[3], careful=False, tcp_target=above_release)
            builder.move("lower", chain[4], careful=True, tcp_target=release)
            builder.gripper("open", "put the object down")
            builder.move("back up", chain[5], careful=True, tcp_target=above_release)
            builder.free_move("to ready", self.ready, via_ready=False)
            info = {"grasp_pose": grasp, "release_pose": release, "object_point": top, "place_point": place,
                    "grasp_depth_m": way.depth, "grasp": way.name}
            return builder.finish(skill, info)
        raise SkillPlanError(_best_failure(failures, "pick"))

    def plan_look(self, q: np.ndarray, base_pose: Sequence[float], point: Sequence[float], *,
                  standoff_m: float | None = None, pitch_deg: float | None = None,
                  surface_z: float | None = None, skill: str = "move_camera") -> SkillPlan:
        """Put the wrist camera ``standoff_m`` from ``point`` (world), looking at it from above and in
        front (``pitch_deg`` below the horizontal); without them the first reachable of `LOOK_VIEWS`."""
        if self.camera is None:
            raise SkillPlanError("look: the planner has no wrist camera frame")
        target = _vector(point, "point")
        builder = _Builder(self, q, base_pose, surface_z)
        base = base_transform(base_pose)
        heading = target[:2] - base[:2, 3]
        if np.linalg.norm(heading) < 0.2:  # right over the base: look along its heading
            heading = base[:2, 0]
        heading = heading / np.linalg.norm(heading)
        views = [(p, d) for p, d in LOOK_VIEWS if (pitch_deg is None or p == pitch_deg)
                 and (standoff_m is None or d == standoff_m)] or [(pitch_deg or 60.0, standoff_m or 0.3)]
        failures = []
        for pitch, distance in views:
            a = math.radians(pitch)
            view = np.array([math.cos(a) * heading[0], math.cos(a) * heading[1], -math.sin(a)])
            x_axis = np.cross(view, [0.0, 0.0, 1.0]) if abs(view[2]) < 0.999 else np.array([1.0, 0.0, 0.0])
            x_axis /= np.linalg.norm(x_axis)
            camera = _pose(np.column_stack([x_axis, np.cross(view, x_axis), view]), target - distance * view)
            try:
                goal = builder.ik(camera, f"wrist camera pose {distance:.2f} m from the point at {pitch:.0f}°",
                                  mode="axis", kinematics=self.camera)
            except SkillPlanError as error:
                failures.append(str(error))
                continue
            builder.free_move("to the view", goal)
            reached = base @ self.camera.forward(goal)
            info = {"camera_pose": reached, "point": target, "standoff_m": distance, "pitch_deg": pitch}
            return builder.finish(skill, info)
        raise SkillPlanError(_best_failure(failures, "look"))

    def plan_joint_move(self, q: np.ndarray, base_pose: Sequence[float], goal: Sequence[float], *,
                        surface_z: float | None = None, skill: str = "move_joints") -> SkillPlan:
        """One free joint-space move of lift and arm to ``goal`` (e.g. folding the arm away)."""
        joints = np.asarray(goal, dtype=float)
        if joints.shape != (self.kin.dof,) or not np.all(np.isfinite(joints)):
            raise SkillPlanError(f"goal: expected {self.kin.dof} finite joint values, got {goal!r}")
        if not self.kin.within_limits(joints):
            raise SkillPlanError(f"goal: {np.round(joints, 3).tolist()} lies outside the joint limits")
        builder = _Builder(self, q, base_pose, surface_z)
        builder.free_move("to the goal", joints)
        return builder.finish(skill, {"goal": joints})

    def plan_stow(self, q: np.ndarray, base_pose: Sequence[float], *, surface_z: float | None = None,
                  skill: str = "stow") -> SkillPlan:
        """Fold the arm into the base from wherever it is. A hand out among things (left at a handle
        or an object by a move that stopped short) first backs straight out along the gripper's axis
        and towards the base (`_off`), as every skill ends: a fold begun at once would swing the hand
        through what it reaches into, and stop on touching it at its first sample. Where no straight
        way back can be planned, the arm folds from where it is."""
        if self.stowed is None:
            raise SkillPlanError("stow: the robot description names no stowed pose")
        builder = _Builder(self, q, base_pose, surface_z)
        if min(np.abs(builder.q - self.stowed).max(), np.abs(builder.q - self.ready).max()) > FOLDED_RAD:
            pose = builder.base @ self.kin.forward(builder.q)
            try:
                back = self._off(builder, builder.q, pose, "the hand's way back")
            except SkillPlanError:
                back = None
            if back is not None:
                builder.move("back off", back, careful=True, tcp_target=builder.base @ self.kin.forward(back[-1]))
        builder.free_move("to the stowed pose", self.stowed)
        return builder.finish(skill, {"goal": self.stowed})

    def _part(self, q: np.ndarray, base_pose: Sequence[float], geometry: PartGeometry, start: float, end: float,
              skill: str, surface_z: float | None, hold: bool = False) -> SkillPlan:
        """Grasp the handle of ``geometry`` (as seen closed) opened by ``start``, move it to ``end``,
        and (unless ``hold``) let go and back off.

        The level grasps are tried first (`skills.arm.grasps.level_grasps`); where none fits (a drawer's bar too low
        over a table for the hand across it), a drawer's bar is grasped from above
        (`skills.arm.grasps.handle_top_grasps`). Whichever way the part moves, the chain is solved
        from the closed grasp outwards (the grasp, then the part's path to its open end, then the
        straight lines off either end of it) and the pieces are put in the order the arm runs
        them; so closing a part takes the posture its opening took, which is known to reach along
        the whole path.
        """
        what = f"{geometry.kind} handle"
        opening = end > start
        step = LINE_STEP_M if geometry.kind == "drawer" else ARC_STEP_RAD
        outer = max(start, end)
        count = max(1, math.ceil(outer / step - 1e-9))
        values = np.linspace(0.0, outer, count + 1)
        path = [grasp_pose(moved_geometry(geometry, float(v))) if v else grasp_pose(geometry) for v in values]
        builder = _Builder(self, q, base_pose, surface_z)
        failures: dict[str, list[str]] = {}
        for way in (*level_grasps(path[0]), *handle_top_grasps(geometry)):
            poses = [pose @ way.offset for pose in path]
            tried = failures.setdefault(way.name, [])
            refusal = _refusal(way, poses, geometry, surface_z, what)
            if refusal:
                tried.append(refusal)
                continue
            chain = self._part_chain(builder, poses, what, opening, way.touch, tried)
            if chain is None:
                continue
            swept, approach, retreat = chain
            grasp, release = (poses[0], poses[-1]) if opening else (poses[-1], poses[0])
            motion = PartMotion(geometry, poses[0][:3, 3], start, end)
            builder.free_move(f"to the pre-grasp pose of the {what}", approach[0])
            name = f"approach the {what} from above" if way.touch else f"approach the {what}"
            self._grasp(builder, way, name, approach, grasp, "handle", what)
            builder.move(f"{'pull' if opening else 'push'} the {geometry.kind} {'open' if opening else 'closed'}",
                         swept, careful=True, tcp_target=release, part_motion=motion)
            if not hold:
                builder.let_go(what, retreat)
            info = {"grasp_pose": grasp, "release_pose": release, "grasp": way.name, "kind": geometry.kind,
                    "start": start, "end": end, "held": hold}
            return builder.finish(skill, info)
        raise SkillPlanError("; ".join(_best_failure(tried, what) if name == "level" else
                                       f"{name}: {_best_failure(tried, what)}" for name, tried in failures.items()))

    def _part_chain(self, builder: _Builder, poses: list[np.ndarray], what: str, opening: bool, touch: bool,
                    failures: list[str]) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
        """(the part's path, approach, retreat) joint waypoints for one grasp variant, each in the
        order the arm runs it (a touch grasp's approach goes on past the grasp, `_searched`, and its
        retreat first lifts off the bar, `_lifted_off`), trying the closed grasp's IK postures in
        turn until one reaches along the whole chain; None (with the reasons in ``failures``) when
        none does."""
        try:
            for closed in builder.solutions(poses[0], f"grasp pose of {what}", restarts=PART_RESTARTS):
                try:
                    swept = builder.path(closed, poses[1:], f"{'opening' if opening else 'closing'} path of {what}")
                    first, last = (closed, swept[-1]) if opening else (swept[-1], closed)
                    grasp = poses[0 if opening else -1]
                    approach = self._off(builder, first, grasp, f"pre-grasp pose of {what}")[::-1]
                    if touch:
                        approach = self._searched(builder, approach, grasp, f"pre-grasp pose of {what}")
                    off = self._lifted_off if touch else self._off
                    retreat = off(builder, last, poses[-1 if opening else 0], f"retreat from {what}")
                    if not opening:
                        swept = swept[::-1]
                except SkillPlanError as error:
                    failures.append(str(error))
                    continue
                return swept, approach, retreat
        except SkillPlanError as error:
            failures.append(str(error))
        return None

    def _searched(self, builder: _Builder, waypoints: np.ndarray, pose: np.ndarray, what: str) -> np.ndarray:
        """``waypoints`` (ending with the TCP at ``pose``) carried on `TOUCH_SEARCH_M` further along
        the gripper's axis: a touch grasp's approach, which stops where the fingertips touch."""
        beyond = builder.path(waypoints[-1], line_poses(pose, pose @ local_pose(z=TOUCH_SEARCH_M), LINE_STEP_M), what)
        return np.vstack([waypoints, beyond[1:]])

    def _lifted_off(self, builder: _Builder, q: np.ndarray, pose: np.ndarray, what: str) -> np.ndarray:
        """`_off` from a touch grasp: the fingertips, resting on the bar and opened along it, first
        lift straight up off it by `LIFT_OFF_M`; backing off along the pitched gripper axis at once
        would drag the bar out with them."""
        up = _shifted(pose, LIFT_OFF_M * UP)
        lift = builder.path(q, line_poses(pose, up, LINE_STEP_M), what)
        return np.vstack([lift, self._off(builder, lift[-1], up, what)[1:]])

    @staticmethod
    def _grasp(builder: _Builder, way: HandleGrasp | ObjectGrasp, name: str, approach: np.ndarray,
               pose: np.ndarray, kind: str, what: str | None = None) -> None:
        """Approach along the joint ``approach`` to the grasp ``pose`` and close on the ``kind``
        ("handle" or "object"): the fingers around it, or, for a touch grasp, the fingers closed
        first and the approach ending where their tips touch it. A touch grasp's approach ends
        past the grasp (`_searched`), so the next move comes back to it; the executor re-times
        that move from wherever the touch stopped the arm."""
        if way.touch:
            builder.gripper("close", "close the fingers")
        builder.move(name, approach, careful=True, stop_on_contact=True, tcp_target=pose,
                     touch=kind if way.touch else None)
        builder.gripper("close", f"grasp the {what or kind}", expect_held=kind)

    def _off(self, builder: _Builder, q: np.ndarray, pose: np.ndarray, what: str) -> np.ndarray:
        """Joint waypoints from ``q`` (the TCP at ``pose``) straight back along the gripper's axis by
        `APPROACH_M`, then, where that is still further out, straight back towards the base until the
        hand is `WITHDRAW_AHEAD_M` ahead of its axis (at the same height and on the same side). The
        second leg is left out when it is out of reach; the first is required."""
        out = pose @ local_pose(z=-APPROACH_M)
        waypoints = builder.path(q, line_poses(pose, out, LINE_STEP_M), what)
        local = builder.to_base @ out
        if local[0, 3] > WITHDRAW_AHEAD_M + 0.02:
            target = local.copy()
            target[0, 3] = WITHDRAW_AHEAD_M
            try:
                back = builder.path(waypoints[-1], line_poses(out, builder.base @ target, LINE_STEP_M),
                                    f"withdrawal from {what}")
            except SkillPlanError:
                return waypoints
            waypoints = np.vstack([waypoints, back[1:]])
        return waypoints


def _refusal(way: HandleGrasp, poses: list[np.ndarray], geometry: PartGeometry, surface_z: float | None,
             what: str) -> str:
    """Why ``way`` cannot hold the handle along ``poses`` ("" when nothing says so): the hand would
    come down onto the surface (at a pose, backed off from it along its axis as approaches and
    retreats are, or, for a touch grasp, searching on past the grasp at either end), or a grasp
    from above would reach into the part's front (the level grasp keeps out in front of it, the
    fingers across the bar)."""
    ends = [poses[0], poses[-1]]
    searched = [pose @ local_pose(z=TOUCH_SEARCH_M) for pose in ends] if way.touch else []
    if surface_z is not None:
        low = min(hand_bottom(pose) for pose in (*poses, *(p @ local_pose(z=-APPROACH_M) for p in poses), *searched))
        if low < surface_z + SURFACE_CLEARANCE_M:
            return (f"clearance: the hand at the {what} ({geometry.handle_point[2]:.3f} m high) would come "
                    f"{surface_z + SURFACE_CLEARANCE_M - low:.3f} m too low over the surface at {surface_z:.3f} m")
    if way.touch:
        gap = min(front_clearance(pose, geometry) for pose in (poses[0], searched[0]))
        if not math.isfinite(gap):
            return f"clearance: how far the front lies behind the {what} is unknown"
        if gap < 0:
            return f"clearance: the hand on the {what} would reach {-gap:.3f} m into the front"
    return ""


class _Builder:
    """Accumulates the steps of one plan from a start configuration, timing IK and Ruckig."""

    def __init__(self, planner: ArmPlanner, q: np.ndarray, base_pose: Sequence[float],
                 surface_z: float | None = None) -> None:
        self.planner = planner
        self.surface_z = surface_z
        kin = planner.kin
        q = np.asarray(q, dtype=float)
        if q.shape != (kin.dof,) or not np.all(np.isfinite(q)):
            raise SkillPlanError(f"start: joint positions {np.round(q, 4).tolist()} are not {kin.dof} finite numbers")
        self.start = kin.clip(q)
        self.q = self.start.copy()
        self.base_pose = tuple(float(v) for v in base_pose)
        self.base = base_transform(self.base_pose)
        self.to_base = np.linalg.inv(self.base)
        self.steps: list[Step] = []
        self.began = time.perf_counter()
        self.ik_s = self.trajectory_s = 0.0
        self.ik_solves = 0
        self.rng = np.random.default_rng(planner.seed)

    def local(self, pose_world: np.ndarray) -> np.ndarray:
        return self.to_base @ pose_world

    def seeds(self, first: np.ndarray | None, target_local: np.ndarray) -> list[np.ndarray]:
        """IK seeds: ``first`` (the previous waypoint of a chain) if given, then the ready pose and
        postures reaching ahead, each turned (joint 1) towards the target and as they are, then
        where the arm is. Seeds close to the target's posture keep IK off contorted solutions."""
        ready = self.planner.ready
        shoulder = ready.copy()
        toward = math.atan2(target_local[1, 3], target_local[0, 3] - 0.08)  # panda_link0 is 8 cm ahead
        postures = [ready, *(np.array(seed) for seed in _AHEAD)]
        turned = []
        for posture in postures:
            seed = posture.copy()
            seed[1] = shoulder[1] + toward
            turned.append(seed)
        seeds = [*turned, *postures, self.q]
        return [first, *seeds] if first is not None else seeds

    def ik(self, pose_world: np.ndarray, what: str, seed: np.ndarray | None = None, mode: IKMode = "pose",
           kinematics: ArmKinematics | None = None) -> np.ndarray:
        """A configuration putting the TCP (or ``kinematics``' frame) at ``pose_world``, tried from a
        few seeds before random restarts; raises SkillPlanError naming ``what``."""
        for q in self.solutions(pose_world, what, seed, mode, kinematics):
            return q
        raise AssertionError("solutions() raises when it finds none")

    def solutions(self, pose_world: np.ndarray, what: str, seed: np.ndarray | None = None, mode: IKMode = "pose",
                  kinematics: ArmKinematics | None = None, restarts: int = 10) -> Iterator[np.ndarray]:
        """Distinct configurations putting the TCP at ``pose_world``: one per seed (`seeds`) that
        converges to a posture not found yet, then up to ``restarts`` from random configurations.
        Raises SkillPlanError naming ``what`` when there is none at all."""
        kin = kinematics or self.planner.kin
        target = self.local(pose_world)
        found: list[np.ndarray] = []
        reason = ""
        starts = [*self.seeds(seed, target), *(kin.random_configuration(self.rng) for _ in range(restarts))]
        for start in starts:
            began = time.perf_counter()
            result = kin.solve_ik(target, kin.clip(start), self.rng, mode=mode, max_restarts=0)
            self.ik_s += time.perf_counter() - began
            self.ik_solves += 1
            if not result.success:
                reason = reason or result.reason
                continue
            if all(np.abs(result.q - other).max() > 0.3 for other in found):
                found.append(result.q)
                yield result.q
        if not found:
            raise SkillPlanError(f"IK: {what} unreachable: {reason}")

    def path(self, start_q: np.ndarray, poses_world: Sequence[np.ndarray], what: str) -> np.ndarray:
        """Joint waypoints (with ``start_q`` first) taking the TCP through ``poses_world``."""
        kin = self.planner.kin
        began = time.perf_counter()
        result = kin.plan_cartesian_path(start_q, [self.local(pose) for pose in poses_world], max_joint_jump=0.35,
                                         max_deviation=0.004)
        self.ik_s += time.perf_counter() - began
        self.ik_solves += len(poses_world)
        if not result.success:
            raise SkillPlanError(f"IK: {what} unreachable: {result.reason}")
        return result.q

    def try_chain(self, stages: list[tuple[str, str, Any]]) -> list[np.ndarray]:
        """Joint waypoints for every stage in turn: ("free", pose) an IK solution (a one-row array),
        ("line", pose) a straight TCP line from the previous pose, ("path", poses) TCP poses."""
        kin = self.planner.kin
        chains: list[np.ndarray] = []
        q = self.q
        pose = None
        for what, kind, target in stages:
            if kind == "free":
                q = self.ik(target, what, seed=None if pose is None else q)
                chains.append(q[None, :])
                pose = target
            elif kind == "line":
                assert pose is not None
                current = self.base @ kin.forward(q)
                chains.append(self.path(q, line_poses(current, target, LINE_STEP_M), what))
                q, pose = chains[-1][-1], target
            else:
                chains.append(self.path(q, list(target), what))
                q, pose = chains[-1][-1], target[-1]
        return chains

    def move(self, name: str, waypoints: np.ndarray, careful: bool, stop_on_contact: bool = False,
             tcp_target: np.ndarray | None = None, part_motion: PartMotion | None = None,
             touch: str | None = None) -> None:
        self.steps.append(self.step(name, waypoints, careful, stop_on_contact, tcp_target, part_motion, touch))
        self.q = self.steps[-1].waypoints[-1].copy()

    def step(self, name: str, waypoints: np.ndarray, careful: bool, stop_on_contact: bool = False,
             tcp_target: np.ndarray | None = None, part_motion: PartMotion | None = None,
             touch: str | None = None) -> Step:
        """A move through joint ``waypoints`` from where the plan has the arm (prepended if missing)."""
        planner = self.planner
        speed = planner.careful_speed if careful else planner.free_speed
        waypoints = np.asarray(waypoints, dtype=float)
        if len(waypoints) and np.abs(waypoints[0] - self.q).max() > 1e-9:
            waypoints = np.vstack([self.q[None, :], waypoints])
        waypoints = planner.kin.clip(waypoints)
        began = time.perf_counter()
        try:
            trajectory = plan_trajectory(waypoints, planner.limits(speed), planner.dt)
        except (RuntimeError, ValueError) as error:
            raise SkillPlanError(f"trajectory: {name}: {error}") from None
        self.trajectory_s += time.perf_counter() - began
        samples = trajectory.positions[1:] if len(trajectory.positions) > 1 else trajectory.positions
        samples = planner.kin.clip(samples)  # Ruckig may overshoot a waypoint on a limit by 1e-16
        return Step("move", name, samples, planner.dt, waypoints, speed, stop_on_contact, tcp_target, part_motion,
                    touch=touch)

    def free_move(self, name: str, goal: np.ndarray, via_ready: bool = True) -> None:
        """A joint-space move to ``goal``, by way of the ready pose when the arm starts or ends stowed
        (the way out of the base and back into it that every skill takes, so folding away from a
        view into a drawer retraces the way there instead of sweeping through the drawer).

        With a known surface the hand must stay `SURFACE_CLEARANCE_M` above it all the way; a
        straight joint-space move that dips lower is replaced by one with the lift raised on the
        way (the arm swings over, then the lift lets it down): by `LIFT_RISES_M` in turn, as little
        as clears the surface (the lift is the slowest joint), and if even the top of its travel
        dips too the plan fails.
        """
        planner = self.planner
        goal = np.asarray(goal, dtype=float)
        start = [self.q]
        stowed = planner.stowed is not None and np.abs(self.q - planner.stowed).max() < FOLDED_RAD
        if via_ready and stowed:
            start.append(planner.ready)
        end = [goal]
        if via_ready and planner.stowed is not None and np.abs(goal - planner.stowed).max() < FOLDED_RAD and not stowed:
            end.insert(0, planner.ready)
        routes = [np.array([*start, *end])]
        lift = planner.lift_index
        if self.surface_z is not None and lift is not None:
            top = planner.kin.upper[lift]
            low_lift = max(start[-1][lift], end[0][lift])
            for rise in (*(r for r in LIFT_RISES_M if low_lift + r < top), math.inf):
                over = [start[-1].copy(), end[0].copy()]
                for q in over:
                    q[lift] = min(top, low_lift + rise)
                routes.append(np.array([*start, *over, *end]))
        target = self.base @ planner.kin.forward(goal)
        low = math.inf
        for waypoints in routes:
            step = self.step(name, waypoints, careful=False, stop_on_contact=True, tcp_target=target)
            low = self.lowest(step)
            if self.surface_z is None or low >= self.surface_z + SURFACE_CLEARANCE_M:
                self.steps.append(step)
                self.q = goal.copy()
                return
        raise SkillPlanError(f"free move: {name}: the hand would come down to {low:.3f} m, "
                             f"{self.surface_z + SURFACE_CLEARANCE_M - low:.3f} m too low over the surface "
                             f"at {self.surface_z:.3f} m, even with the lift up")

    def lowest(self, step: Step) -> float:
        """The lowest the hand gets (world z, `hand_bottom`) over a move's samples."""
        assert step.samples is not None
        kin = self.planner.kin
        picks = np.unique(np.r_[np.arange(0, len(step.samples), 3), len(step.samples) - 1])
        return min(hand_bottom(self.base @ kin.forward(step.samples[k]), self.base, self.planner.body_radius)
                   for k in picks)

    def gripper(self, action: str, name: str, expect_held: str | None = None) -> None:
        self.steps.append(Step("gripper", name, action=action, expect_held=expect_held))

    def let_go(self, what: str, retreat: np.ndarray) -> None:
        """Open the hand on ``what`` and back off along ``retreat``, as every part skill ends."""
        self.gripper("open", f"let go of the {what}")
        self.move(f"back off the {what}", retreat, careful=True,
                  tcp_target=self.base @ self.planner.kin.forward(retreat[-1]))

    def finish(self, skill: str, info: dict[str, Any]) -> SkillPlan:
        planning_ms = 1e3 * (time.perf_counter() - self.began)
        return SkillPlan(skill, tuple(self.steps), self.base_pose, self.start, self.q.copy(), 1e3 * self.ik_s,
                         self.ik_solves, 1e3 * self.trajectory_s, planning_ms, info)


def _check_amount(geometry: PartGeometry, amount: float) -> None:
    limit, unit = (0.6, "m") if geometry.kind == "drawer" else (math.pi, "rad")
    if not (math.isfinite(amount) and 0 < amount <= limit):
        raise SkillPlanError(f"amount: {amount!r} {unit} must lie in (0, {limit:g}] for a {geometry.kind}")


def _vector(value: Sequence[float], name: str) -> np.ndarray:
    vector = np.asarray(value, dtype=float)
    if vector.shape != (3,) or not np.all(np.isfinite(vector)):
        raise SkillPlanError(f"{name}: expected 3 finite numbers, got {value!r}")
    return vector


def _pose(rotation: np.ndarray, position: np.ndarray) -> np.ndarray:
    pose = np.eye(4)
    pose[:3, :3], pose[:3, 3] = rotation, position
    return pose


def _shifted(pose: np.ndarray, offset: np.ndarray) -> np.ndarray:
    moved = pose.copy()
    moved[:3, 3] += offset
    return moved


def _best_failure(failures: list[str], what: str) -> str:
    """The failure of the variant that got furthest (stages are tried in order), and how many were tried."""
    if not failures:
        return f"{what}: no variant to try"
    stages = ("above", "wrist", "grasp", "down", "lift", "carry", "lower", "opening", "closing", "pre-grasp",
              "retreat", "back")

    def progress(message: str) -> int:
        return max((k for k, word in enumerate(stages) if f"IK: {word}" in message), default=-1)

    best = max(failures, key=progress)
    return f"{best} (and {len(failures) - 1} other grasp variants failed)" if len(failures) > 1 else best
