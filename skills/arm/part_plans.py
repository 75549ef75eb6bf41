"""Plans for doors and drawers: open, close, and push shut a part held open.

A part skill is a free move to a staging pose, a straight line out to the pre-grasp pose
(`skills.arm.grasp_lines.APPROACH_M` out along the gripper's axis) and in onto the handle, close,
follow the part's path (a line for drawers, an arc about the hinge for doors, the TCP turning with
the door), open, back out along the gripper's axis and withdraw straight towards the base (the
staging pose is the same withdrawal ahead of the pre-grasp, so closing starts where opening
ended). The chain is solved from the closed grasp outwards whichever way the part moves, so a
close takes the posture its open took.

Grasp variants (the hand turned half a turn about its axis, tilted about the bar:
`skills.arm.grasps.level_grasps`) and the grasp's IK postures (structured seeds, then a few random
restarts) are tried in turn until one chain is reachable throughout; with ``keep_off`` (what stands
near: `skills.arm.clearance.Clearance`), first until one along which the whole arm and the hand
keep clear of it, and the free move to the staging pose takes a route that does; with
``part_points`` that free move keeps off the part itself too. With ``surface_z`` (a table's top)
variants whose hand would come down onto it are refused (`skills.arm.grasps.HAND_BOXES`): a bar
less than ~9 cm above the table cannot be grasped by a Panda hand 21 cm tall across its fingers.
A drawer's bar is then grasped from above, the fingers closed and their tips brought down onto it
until they touch (`skills.arm.grasps.handle_top_grasps`). An opening may end holding the
handle (``hold``); `plan_close_held` then pushes the part shut from that grasp.
"""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np

from agent.perception.grasp_poses import grasp_pose
from agent.perception.part_geometry import PartGeometry
from agent.perception.part_motion import moved_geometry, part_motion
from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.clearance import Clearance
from skills.arm.frames import base_transform
from skills.arm.grasp_lines import APPROACH_M, backed_off, lifted_off, searched
from skills.arm.grasps import (
    TOUCH_SEARCH_M,
    HandleGrasp,
    front_clearance,
    hand_bottom,
    handle_top_grasps,
    level_grasps,
    local_pose,
)
from skills.arm.ik_search import LINE_STEP_M, IKSearch
from skills.arm.plan_builder import SURFACE_CLEARANCE_M, PlanBuilder
from skills.arm.skill_plan import PartMotion, SkillPlan, SkillPlanError, best_failure

#: Cartesian step of door arcs (rad).
ARC_STEP_RAD = math.radians(1.5)
#: Random IK restarts tried for a handle's grasp, per grasp variant, after the structured seeds.
PART_RESTARTS = 4
#: How far past where it was seen shut a part is pushed (m for drawers), to its end stop.
PUSH_PAST = {"drawer": 0.015}
#: A part's path solved anew is the one the arm holding it is on when it passes within this (rad or
#: m, any joint) of where the arm is.
HELD_MATCH_RAD = 0.05

#: One grasp posture's joint waypoints: the part's path, the approach and the retreat.
_Chain = tuple[np.ndarray, np.ndarray, np.ndarray]


def plan_open(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, geometry: PartGeometry, amount: float, *,
              surface_z: float | None = None, skill: str | None = None, hold: bool = False,
              keep_off: np.ndarray | None = None, part_points: np.ndarray | None = None) -> SkillPlan:
    """Open a door or drawer (see the module doc).

    Args:
        arm: the arm planned for.
        q: where the arm is.
        base_pose: where the base stands.
        geometry: the part as seen closed.
        amount: how far to open it (m for drawers, rad for doors).
        surface_z: the top of what the furniture stands on (a table); the hand keeps above it.
        skill: the plan's name (default ``open_<kind>``).
        hold: end holding the handle, the part pulled open (no letting go, no backing off): it
            cannot swing on or be knocked while the robot looks, and `plan_close_held` shuts it
            again without a second grasp.
        keep_off: (N, 3) points of what stands near, neither the part nor its piece: the chain and
            its free move keep clear of them where a grasp posture lets them.
        part_points: (N, 3) points of the part and of its piece's handles where they stand now: the
            free move to the handle keeps off them (a door standing open lies across the way to its
            handle, a drawer's handle beside a door's), and the links keep off the part on the way in.

    Returns:
        The plan; ``info`` has the grasp and release poses and the grasp variant taken.

    Raises:
        SkillPlanError: a bad amount, or no grasp variant reaches along the whole chain.
    """
    _check_amount(geometry, amount)
    return _plan_part(arm, q, base_pose, geometry, 0.0, float(amount), skill or f"open_{geometry.kind}", surface_z,
                      hold, keep_off, part_points)


def plan_close(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, geometry: PartGeometry, amount: float, *,
               geometry_is_open: bool = False, surface_z: float | None = None,
               skill: str | None = None, keep_off: np.ndarray | None = None,
               part_points: np.ndarray | None = None) -> SkillPlan:
    """Close a door or drawer that stands open, taking the posture its opening took.

    Args:
        arm: the arm planned for.
        q: where the arm is.
        base_pose: where the base stands.
        geometry: the part as seen closed (what its opening used), or as seen now with ``geometry_is_open``.
        amount: how far it stands open (m or rad).
        geometry_is_open: ``geometry`` is the part as seen open.
        surface_z: as for `plan_open`.
        skill: the plan's name (default ``close_<kind>``).
        keep_off: as for `plan_open`.
        part_points: as for `plan_open`.

    Returns:
        The plan.

    Raises:
        SkillPlanError: a bad amount, or no grasp variant reaches along the whole chain.
    """
    _check_amount(geometry, amount)
    if geometry_is_open:
        geometry = moved_geometry(geometry, -float(amount))
    return _plan_part(arm, q, base_pose, geometry, float(amount), 0.0, skill or f"close_{geometry.kind}", surface_z,
                      keep_off=keep_off, part_points=part_points)


def plan_close_held(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, geometry: PartGeometry, amount: float, *,
                    surface_z: float | None = None, skill: str | None = None) -> SkillPlan:
    """Shut a part that stands open with the hand on its handle, without a second grasp.

    The hand rides the handle back along the part's path from the grasp it has now (whichever
    variant the opening took, read off ``q``), a drawer on past where it was seen shut by
    `PUSH_PAST` as `plan_close` pushes it (pushed only to there, drawers held open while the robot
    looked stood 10–14 mm out, counted open: occlusion 1031 and 1065 of tuning-wide), lets go and
    backs off as `plan_close` would.

    Args:
        arm: the arm planned for.
        q: where the arm is, holding the handle.
        base_pose: where the base stands.
        geometry: the part as seen closed.
        amount: how far it stands open (m or rad).
        surface_z: as for `plan_open`.
        skill: the plan's name (default ``close_<kind>``).

    Returns:
        The plan.

    Raises:
        SkillPlanError: a bad amount, or the closing path is out of reach.
    """
    _check_amount(geometry, amount)
    what = f"{geometry.kind} handle"
    here = arm.start_configuration(q)
    ik = IKSearch(arm, here, base_pose)
    builder = PlanBuilder(arm, here, base_pose, surface_z)
    grasp = builder.base @ arm.kin.forward(here)
    held = np.linalg.inv(grasp_pose(moved_geometry(geometry, amount))) @ grasp
    step = LINE_STEP_M if geometry.kind == "drawer" else ARC_STEP_RAD
    values, shut = _pushed_past(geometry, np.linspace(0.0, float(amount), max(1, math.ceil(amount / step - 1e-9)) + 1))
    poses = [grasp_pose(moved_geometry(geometry, float(v))) @ held for v in values]
    try:
        swept = ik.path(here, poses[::-1][1:], f"closing path of {what}")
    except SkillPlanError as error:
        swept = _retraced(ik, poses, what, error)
    retreat = backed_off(ik, swept[-1], poses[0], f"retreat from {what}")
    builder.move(f"push the {geometry.kind} closed", swept, careful=True, tcp_target=poses[0],
                 part_motion=PartMotion(geometry, poses[shut][:3, 3], float(amount), 0.0))
    builder.let_go(what, retreat)
    info = {"grasp_pose": grasp, "release_pose": poses[0], "kind": geometry.kind, "start": float(amount),
            "end": 0.0, "held": True}
    return builder.finish(skill or f"close_{geometry.kind}", info, ik)


def _pushed_past(geometry: PartGeometry, values: np.ndarray) -> tuple[np.ndarray, int]:
    """The openings of a part's path to shut, ``values`` (from 0, as seen shut, out), led by
    `PUSH_PAST` beyond shut where its kind has one; and the index of the opening 0 among them."""
    past = PUSH_PAST.get(geometry.kind, 0.0)
    return (np.r_[-past, values], 1) if past else (values, 0)


def _retraced(ik: IKSearch, poses: list[np.ndarray], what: str, error: SkillPlanError) -> np.ndarray:
    """The joint path of ``poses`` (closed to open) solved outwards from the closed grasp as an
    opening solves it, reversed: IK tracked backwards from the open end of a redundant arm
    drifts and may jump where the opening's own path did not. Taken only when it ends (at the
    open end) where the arm is; else ``error``."""
    for closed in ik.solutions(poses[0], f"grasp pose of {what}", restarts=PART_RESTARTS):
        try:
            out = ik.path(closed, poses[1:], f"opening path of {what}")
        except SkillPlanError:
            continue
        if np.abs(out[-1] - ik.here).max() < HELD_MATCH_RAD:
            return out[::-1]
    raise error


def _plan_part(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, geometry: PartGeometry, start: float, end: float,
               skill: str, surface_z: float | None, hold: bool = False,
               keep_off: np.ndarray | None = None, part_points: np.ndarray | None = None) -> SkillPlan:
    """Grasp the handle of ``geometry`` (as seen closed) opened by ``start``, move it to ``end``,
    and (unless ``hold``) let go and back off.

    A drawer pushed shut is pushed on `PUSH_PAST` beyond where it was seen shut, until it stops
    against the end of its travel: seen from before it, a shut drawer's handle is placed a
    centimetre or so out, and a drawer pushed only that far stood 9–11 mm out, more than the 5 % of
    its travel that counts as shut. The level grasps are tried first; where none fits (a drawer's
    bar too low over a table for the hand across it), a drawer's bar is grasped from above.
    Whichever way the part moves, the chain is solved from the closed grasp outwards (the grasp,
    then the part's path to its open end, then the straight lines off either end of it) and the
    pieces are put in the order the arm runs them; so closing a part takes the posture its opening
    took, which is known to reach along the whole path. With ``keep_off``, the first chain of any
    grasp variant along which the arm and hand keep clear of it, and the links of ``part_points`` on
    the way in, is taken (`_part_chains`, `_chain_problem`), and the free move to it keeps clear of
    both; of those, the first whose back-off keeps the links off the part where it is left goes
    first (backing off an open door's handle, the forearm lying along the leaf pushed the door on by
    0.3 rad and was held back against it: occlusion 1052 of tuning-wide); where none does, the plan
    is the one made without them: the first chain that reaches, its free move kept off only
    ``part_points``. What stands near is known only by the points seen of it, and a posture that
    touches a voxel of it is still better than no plan. The hand is on the part from the grasp on,
    and the part moves: its points count for the links on the way in and for the free move, not for
    the hand at the grasp or along the part's path (recursive 1025 of tuning-wide: on its way to an
    open door's handle, the arm came down on the door, and the door was left open).
    """
    what = f"{geometry.kind} handle"
    opening = end > start
    step = LINE_STEP_M if geometry.kind == "drawer" else ARC_STEP_RAD
    outer = max(start, end)
    count = max(1, math.ceil(outer / step - 1e-9))
    values, shut = np.linspace(0.0, outer, count + 1), 0
    if not opening and end == 0.0:  # shut: on past where it was seen shut, until it stops against its end
        values, shut = _pushed_past(geometry, values)
    path = [grasp_pose(moved_geometry(geometry, float(v))) if v else grasp_pose(geometry) for v in values]
    here = arm.start_configuration(q)
    ik = IKSearch(arm, here, base_pose)
    base = base_transform(base_pose)
    near, own = (np.zeros((0, 3)) if points is None else np.asarray(points, dtype=float).reshape(-1, 3)
                 for points in (keep_off, part_points))
    clearance = Clearance(arm, base, surface_z, near) if len(near) else None
    itself = Clearance(arm, base, surface_z, own) if len(own) else None
    left = None if hold or not len(own) else Clearance(arm, base, surface_z, _moved(own, geometry, start, end))
    checked = clearance is not None or itself is not None
    builder = PlanBuilder(arm, here, base_pose, surface_z, itself)
    failures: dict[str, list[str]] = {}
    # the chain taken without the check: the first that reaches, of the first variant that has one
    fallback: tuple[HandleGrasp, list[np.ndarray], _Chain] | None = None
    # the first chain clear of what stands near whose back-off sweeps the part where it was left
    brushing: tuple[HandleGrasp, list[np.ndarray], _Chain] | None = None
    for way in (*level_grasps(path[0]), *handle_top_grasps(geometry)):
        poses = [pose @ way.offset for pose in path]
        tried = failures.setdefault(way.name, [])
        refusal = _refusal(way, poses[shut:], geometry, surface_z, what)  # pushed past, the front goes too
        if refusal:
            tried.append(refusal)
            continue
        for chain in _part_chains(ik, poses, what, opening, way.touch, tried):
            if not checked:
                fallback = fallback or (way, poses, chain)
                break
            if _chain_problem(clearance, itself, chain) is None:
                if left is None or left.path_problem(chain[2], every=2) is None:
                    builder.clearance = Clearance(arm, base, surface_z, np.vstack([near, own]))
                    return _build(builder, ik, geometry, way, poses, chain, (start, end), shut, skill, hold, clear=True)
                brushing = brushing or (way, poses, chain)
            fallback = fallback or (way, poses, chain)
        if not checked and fallback is not None:
            break
    if brushing is not None:
        builder.clearance = Clearance(arm, base, surface_z, np.vstack([near, own]))
        return _build(builder, ik, geometry, *brushing, (start, end), shut, skill, hold, clear=True)
    if fallback is not None:
        return _build(builder, ik, geometry, *fallback, (start, end), shut, skill, hold, clear=False)
    raise SkillPlanError("; ".join(best_failure(tried, what) if name == "level" else
                                   f"{name}: {best_failure(tried, what)}" for name, tried in failures.items()))


def _build(builder: PlanBuilder, ik: IKSearch, geometry: PartGeometry, way: HandleGrasp, poses: list[np.ndarray],
           chain: _Chain, travel: tuple[float, float], shut: int, skill: str,
           hold: bool, clear: bool) -> SkillPlan:
    """The plan of one grasp variant's chain (`_part_chains`): the free move to the staging pose,
    the approach and grasp, the part's path from ``travel[0]`` to ``travel[1]``, and unless
    ``hold`` letting go and backing off; ``clear`` says whether the chain was checked clear."""
    what = f"{geometry.kind} handle"
    start, end = travel
    opening = end > start
    swept, approach, retreat = chain
    grasp, release = (poses[0], poses[-1]) if opening else (poses[-1], poses[0])
    motion = PartMotion(geometry, poses[shut][:3, 3], start, end)
    builder.free_move(f"to the pre-grasp pose of the {what}", approach[0])
    name = f"approach the {what} from above" if way.touch else f"approach the {what}"
    builder.grasp(way, name, approach, grasp, "handle", what)
    builder.move(f"{'pull' if opening else 'push'} the {geometry.kind} {'open' if opening else 'closed'}",
                 swept, careful=True, tcp_target=release, part_motion=motion)
    if not hold:
        builder.let_go(what, retreat)
    info = {"grasp_pose": grasp, "release_pose": release, "grasp": way.name, "kind": geometry.kind,
            "start": start, "end": end, "held": hold, "clear": clear}
    return builder.finish(skill, info, ik)


def _moved(points: np.ndarray, geometry: PartGeometry, start: float, end: float) -> np.ndarray:
    """The part's ``points``, remembered opened by ``start``, where they stand opened by ``end``."""
    motion = part_motion(geometry, end) @ np.linalg.inv(part_motion(geometry, start))
    return points @ motion[:3, :3].T + motion[:3, 3]


def _chain_problem(near: Clearance | None, itself: Clearance | None, chain: _Chain) -> str | None:
    """What the arm or the hand would touch of what stands near along a part's chain, or what the
    links would touch of the part itself on the way in to its handle (every other waypoint); None
    for nothing. The part is where it stands before the chain: once it moves, its points are not."""
    for waypoints in chain if near is not None else ():
        problem = near.path_problem(waypoints, every=2, hand=True)
        if problem is not None:
            return problem
    return None if itself is None else itself.path_problem(chain[1], every=2)  # the approach


def _part_chains(ik: IKSearch, poses: list[np.ndarray], what: str, opening: bool, touch: bool,
                 failures: list[str]) -> Iterator[_Chain]:
    """(the part's path, approach, retreat) joint waypoints for one grasp variant, each in the
    order the arm runs it (a touch grasp's approach goes on past the grasp, `searched`, and its
    retreat first lifts off the bar, `lifted_off`), for each of the closed grasp's IK postures in
    turn that reaches along the whole chain (the reasons of those that do not go to
    ``failures``)."""
    try:
        for closed in ik.solutions(poses[0], f"grasp pose of {what}", restarts=PART_RESTARTS):
            try:
                swept = ik.path(closed, poses[1:], f"{'opening' if opening else 'closing'} path of {what}")
                first, last = (closed, swept[-1]) if opening else (swept[-1], closed)
                grasp = poses[0 if opening else -1]
                approach = backed_off(ik, first, grasp, f"pre-grasp pose of {what}")[::-1]
                if touch:
                    approach = searched(ik, approach, grasp, f"pre-grasp pose of {what}")
                off = lifted_off if touch else backed_off
                retreat = off(ik, last, poses[-1 if opening else 0], f"retreat from {what}")
                if not opening:
                    swept = swept[::-1]
            except SkillPlanError as error:
                failures.append(str(error))
                continue
            yield swept, approach, retreat
    except SkillPlanError as error:
        failures.append(str(error))


def _refusal(way: HandleGrasp, poses: list[np.ndarray], geometry: PartGeometry, surface_z: float | None,
             what: str) -> str:
    """Why ``way`` cannot hold the handle along ``poses`` ("" when nothing says so): the hand would
    come down onto the surface (at a pose, backed off from it along its axis as approaches and
    retreats are, or, for a touch grasp, searching on past the grasp at either end), or a grasp
    from above would reach into the part's front (the level grasp keeps out in front of it, the
    fingers across the bar)."""
    ends = [poses[0], poses[-1]]
    searched_to = [pose @ local_pose(z=TOUCH_SEARCH_M) for pose in ends] if way.touch else []
    if surface_z is not None:
        low = min(hand_bottom(pose) for pose in (*poses, *(p @ local_pose(z=-APPROACH_M) for p in poses),
                                                 *searched_to))
        if low < surface_z + SURFACE_CLEARANCE_M:
            return (f"clearance: the hand at the {what} ({geometry.handle_point[2]:.3f} m high) would come "
                    f"{surface_z + SURFACE_CLEARANCE_M - low:.3f} m too low over the surface at {surface_z:.3f} m")
    if way.touch:
        gap = min(front_clearance(pose, geometry) for pose in (poses[0], searched_to[0]))
        if not math.isfinite(gap):
            return f"clearance: how far the front lies behind the {what} is unknown"
        if gap < 0:
            return f"clearance: the hand on the {what} would reach {-gap:.3f} m into the front"
    return ""


def _check_amount(geometry: PartGeometry, amount: float) -> None:
    limit, unit = (0.6, "m") if geometry.kind == "drawer" else (math.pi, "rad")
    if not (math.isfinite(amount) and 0 < amount <= limit):
        raise SkillPlanError(f"amount: {amount!r} {unit} must lie in (0, {limit:g}] for a {geometry.kind}")
