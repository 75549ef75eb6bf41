"""Plans for picking an object away and back: top-down, or, under a board, by its side.

Above the object (in from higher up, straight down: `HIGH_ABOVE_M`), down onto its top (the
fingers closing across the line of sight from the robot where the object fits that way, since
perception places things worst along it, unless the hand would touch less of what stands near
coming down another way; an object wider than the opening is held by the closed fingertips
brought down onto its top until they touch, `skills.arm.grasps.object_grasps`), close, lift,
carry at height, lower until the object stands a little above where it should, or until it meets
what it is put on first (a top a little higher than the memory had it holds the arm back without
the arm touching anything: the world puts a released object down onto whatever is under it),
open, back up, ready. Under a board close over it (a box in a cabinet), the hand takes its top's
near edge leaning back towards the robot, or, where the board leaves too little room for that
wrist, the side facing the robot, the hand level (`skills.arm.grasps.side_grasps`); the object is
drawn straight out of the storage, and the hand backs off it level after letting go. What stands
over and around the object, and the room it leaves, is `skills.arm.headroom`'s.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.clearance import Carried, Clearance, box_points
from skills.arm.frames import base_transform, pose_at, shifted
from skills.arm.grasp_lines import APPROACH_M, searched
from skills.arm.grasps import UP, ObjectGrasp, hand_touches, local_pose, object_grasps, side_grasps
from skills.arm.headroom import (LIFT_M, LIFT_SPARE_M, confined, headroom, over_the_rim, over_the_way, too_low_to_lift,
                                 under_a_board)
from skills.arm.ik_search import IKSearch, PostureCheck
from skills.arm.plan_builder import PlanBuilder
from skills.arm.skill_plan import SkillPlan, SkillPlanError, best_failure, checked_vector

#: How far (m) open fingers must clear an object on either side to close around it; else they rest
#: on its top. The memory places things to within its 1 cm voxels: a 7 cm carton in the 8 cm
#: opening, 5 mm either side, was missed by a finger landing on its top.
STRADDLE_CLEARANCE_M = 0.008
#: The hand comes to the pose above an object from this much (m) higher, straight down, where
#: nothing remembered stands up there: a free move's joint path to that pose swept a finger across
#: the top of a 20 cm milk carton put down near the base, which stopped the pick back (occlusion
#: 1000 of tuning-wide).
HIGH_ABOVE_M = 0.12
#: The stages of a pick in which the hand carries the object, and those on the way to it.
_CARRYING = frozenset({"lift", "out", "carry", "in", "lower"})
_COMING = frozenset({"high above the object", "above the object", "before the object",
                     "well before the object's side", "before the object's side"})
#: The stages in which the object is lifted clear of where it stood and of where it goes.
_LIFTED = frozenset({"out", "carry", "in"})
#: The grasps of an object's top near its edge and of its side, tried only under a board.
EDGE, SIDE = "fingertips-on-near-edge", "fingertips-on-near-side"
#: How much room (m) over an object's top a hand on its near edge needs for its wrist, leaning back
#: 65° (`skills.arm.grasps.EDGE_PITCHES`), the steepest tried; under a board lower than that over
#: the lift, the grasps of its side are tried first (`_clear_routes`).
LEANING_ROOM_M = 0.19
#: How far over the surface (m) an object's bottom stands where it stands in storage, drawn out
#: over the front of what it stands in (`skills.arm.headroom.over_the_rim`'s ``out``).
IN_STORAGE_M = 0.03
#: How far before the pose above the object (towards the robot, m) the hand may come in from.
BEFORE_M = (0.15, 0.3, 0.45)
#: A low lift clears the object's own height by `skills.arm.headroom.LIFT_SPARE_M`, and is never
#: lower than this (m) (`_lifts`).
LOW_LIFT_M = 0.05
#: Grasps of the middle of an object tried for a chain clear all the way, best first, before the
#: grasps of its near edge and settling for one that merely reaches; routes tried so at the most.
CLEAR_GRASPS, CLEAR_ROUTES = 4, 48
#: How far (m) a carry in the open goes round by the robot's side when straight across is not clear.
DETOUR_M = 0.25
#: The highest (m) a carry in the open is raised to pass over what stands in its way
#: (`skills.arm.headroom.over_the_way`); what stands higher is gone round (`DETOUR_M`).
HIGHEST_LIFT_M = 0.3


def plan_pick(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, object_point: Sequence[float],
              extent: Sequence[float], place_point: Sequence[float], *, skill: str = "pick_away",
              surface_z: float | None = None, lift_m: float = LIFT_M, clearance_m: float = 0.015,
              grasp_depth_m: float | None = None, keep_off: np.ndarray | None = None,
              grasp_first: ObjectGrasp | None = None) -> SkillPlan:
    """Pick an object and put it down elsewhere (see the module doc).

    Args:
        arm: the arm planned for.
        q: where the arm is.
        base_pose: where the base stands.
        object_point: the object's top grasp point (world).
        extent: its box (dx, dy, dz).
        place_point: where that point should end, less ``clearance_m``; or (k, 3) such places, to
            take the first a chain clear all the way reaches (the first when none does).
        skill: the plan's name.
        surface_z: the table's top, which free moves keep the hand above.
        lift_m: how high above the grasp and the release the object is carried.
        clearance_m: how far above ``place_point`` the object is let go.
        grasp_depth_m: how far below its top the fingers close around it (default: from its height).
        keep_off: (N, 3) points of what stands near, neither the object nor what it stands on:
            the grasps whose hand would touch fewer of them, coming down onto the object and onto
            the place, are tried first.
        grasp_first: a grasp to seek a clear chain by before all others
            (``info["grasp_way"]`` of the pick that took the object out): a box taken out of a
            cabinet by its near edge, grasped again by the edge nearest the robot where it stood on
            the table, came into the cabinet turned, and no route put it back (recursive 1025 of
            tuning-wide). Fingers closing around the object in the open are not: the usual grasps
            close across the line of sight, where the memory places things best, and a bottle held
            again as it had been taken away, across the line of sight from where it stood, was
            missed (occlusion 1027). Fingertips on a wide box's top are, wherever it stands.

    Returns:
        The plan; ``info["grasp"]`` says whether the fingers close around the object or their tips
        rest on its top (``info["grasp_way"]``: the grasp itself), ``info["place_point"]`` where it goes.

    Raises:
        SkillPlanError: a bad argument, or no grasp reaches along the whole chain.
    """
    top = checked_vector(object_point, "object_point")
    places = np.asarray(place_point, dtype=float)
    places = [checked_vector(point, "place_point") for point in (places if places.ndim == 2 else [place_point])]
    if not places:
        raise SkillPlanError("place_point: no place given")
    size = checked_vector(extent, "extent")
    if np.any(size <= 0):
        raise SkillPlanError(f"pick: extent {np.round(size, 3).tolist()} must be positive")
    depth = grasp_depth_m if grasp_depth_m is not None else min(0.025, max(0.005, size[2] / 2 - 0.005))
    if too_low_to_lift(top, size, keep_off, least := _lifts(lift_m, size)[-1]):
        raise SkillPlanError(f"pick: no room to lift it: what stands over it is "
                             f"{headroom(top, size, keep_off, least):.3f} m over its top, and it is lifted "
                             f"{least:.3f} m at the least, clear of its own height (of what it may cover)")
    lift_m = max(lift_m, *(over_the_rim(point, size, keep_off, _drawn_out(base_pose, point, size, surface_z))
                           for point in (top, *places)))
    here = arm.start_configuration(q)
    ik = IKSearch(arm, here, base_pose)
    near = np.zeros((0, 3)) if keep_off is None else np.asarray(keep_off, dtype=float).reshape(-1, 3)
    clearance = Clearance(arm, base_transform(base_pose), surface_z, near)
    # On the way to it, the object is in the way too: a finger swept across a carton's top.
    around = Clearance(arm, base_transform(base_pose), surface_z,
                       np.vstack([near, box_points(top - size[2] / 2 * UP, size)]))
    builder = PlanBuilder(arm, here, base_pose, surface_z, around)
    failures: list[str] = []
    toward = _toward(base_pose, top)
    grasps = [*object_grasps(size, top, base_pose, arm.gripper_opening - 2 * STRADDLE_CLEARANCE_M, depth),
              *side_grasps(size, top, base_pose)]
    room = min(headroom(point, size, keep_off, lift_m + LEANING_ROOM_M) for point in (top, *places))

    def clear_routes(choices: list[ObjectGrasp]) -> tuple[list[list[_Way]], list[tuple[_Route, bool]]]:
        ways_to = [_ways(choices, top, place, size, lift_m, clearance_m, keep_off) for place in places]
        return ways_to, [(route, True) for place, ways in zip(places, ways_to, strict=True)
                         for route in _clear_routes(ways, lift_m, size, keep_off, toward, _toward(base_pose, place),
                                                    room, over_the_way(top, place, size, keep_off))]

    # A chain clear of everything all the way, to each place in turn (a few dozen routes at most
    # each, the likeliest first), by ``grasp_first`` before any other; else, as without such
    # checks, to the first place, the first grasp that reaches at all, unless it is confined
    # (`_plain_routes`) or carries the object into what stands near (`_carried_into`).
    first = [] if grasp_first is None else [(route, clear) for route, clear in clear_routes([grasp_first])[1]
                                             if grasp_first.touch or np.any(route.inward) or np.any(route.out)]
    ways_to, routes = clear_routes(grasps)
    routes = [*first, *routes, *((route, False) for route in _plain_routes(ways_to[0], lift_m, keep_off))]
    carried_into = False
    for route, clear in routes:
        way, grasp, release = route.way, route.grasp, route.release
        carried = Carried.held_at(grasp, top - size[2] / 2 * UP, size)

        def check(what: str, posture: np.ndarray) -> str | None:
            if what in _COMING:
                return around.problem(posture, hand=True)
            return clearance.problem(posture, carried if what in _CARRYING else None, lifted=what in _LIFTED)

        stages = route.stages()
        try:
            if not clear:
                chains = ik.chain(stages)
                if _carried_into(clearance, dict(zip((stage[0] for stage in stages), chains))["carry"], carried):
                    carried_into = True
                    continue
            elif np.any(route.inward):  # into storage: from inside it first, then as it came
                chains = _retraced(ik, stages, check, route.backs_off) or ik.clear_chain(stages, check)
            else:
                chains = ik.clear_chain(stages, check)
            if chains is None:
                continue
            named = dict(zip((stage[0] for stage in stages), chains))
            down = route.down
            if way.touch:
                named[down] = searched(ik, named[down], grasp, down, straight_down=not route.backs_off)
        except SkillPlanError as error:
            failures.append(str(error))
            continue
        place = release[:3, 3] - way.offset - (clearance_m - way.depth) * UP
        # Away from it, the arm keeps off the thing just put down: a hand backed off level from a
        # box's side, low beside it, swept a finger into it on its way to the ready pose (recursive
        # 1075 of tuning-wide).
        leaving = Clearance(arm, base_transform(base_pose), surface_z,
                            np.vstack([near, box_points(place - size[2] / 2 * UP, size)]))
        route.build(builder, named, leaving)
        info = {"grasp_pose": grasp, "release_pose": release, "object_point": top, "place_point": place,
                "grasp_depth_m": way.depth, "grasp": way.name, "grasp_way": way, "lift_m": route.lift, "clear": clear}
        return builder.finish(skill, info, ik)
    if carried_into:
        raise SkillPlanError("pick: no route clear of what stands near, and every route taken unchecked that reaches "
                             "would carry it through what stands near")
    if not failures:
        raise SkillPlanError("pick: no route clear of what stands near, and none is taken unchecked under a board "
                             "close over the object or its place")
    raise SkillPlanError(best_failure(failures, "pick"))


def _carried_into(clearance: Clearance, waypoints: np.ndarray, carried: Carried) -> bool:
    """Whether the thing carried along ``waypoints`` would pass through what stands near
    (`Clearance.carried_meets`). A route taken unchecked is still not carried into what stands
    near: at the back of a table, where no route reached clear, the box carried straight across to
    its place met the chest beside it and pushed its drawers 56 cm in (recursive 1144 of
    tuning-wide). Only passing through counts: a milk carton carried 1.5 cm by a door's handle, as
    close as no checked route may come, went by it (occlusion 1019)."""
    return any(clearance.carried_meets(q, carried) for q in waypoints)


def _retraced(ik: IKSearch, stages: list[tuple[str, str, Any]], check: PostureCheck, backs_off: bool = False
              ) -> list[np.ndarray] | None:
    """The waypoints of a chain clear all the way (`IKSearch.clear_chain`) worked out from where
    it lets go back to where it begins, then turned round: the arm postures inside the storage
    the object goes into are those a pick out of it found, and the way out of there is the way in.
    Worked out forwards, from the object on the table, the carry into a cabinet came with postures
    whose links touched the cabinet on every route, and a box taken out of it by a checked route
    could not be put back (recursive 1025 of tuning-wide).

    Args:
        stages: the route's stages (`_Route.stages`): a free one, lines, and the back-up last.
        check: as for `IKSearch.clear_chain`.
        backs_off: the back-up is a line of its own (a hand at the object's side backs off level),
            worked out with the others, where it otherwise retraces the lowering.

    Returns:
        Each stage's waypoints in the order of ``stages``, or None where no posture passes.
    """
    forward = stages if backs_off else stages[:-1]  # else the back-up retraces the lowering
    last = len(forward) - 1
    backwards = [(forward[last][0], "free", forward[last][2])]
    backwards += [(forward[k][0], "line", forward[k - 1][2]) for k in range(last, 0, -1)]
    found = ik.clear_chain(backwards, check)
    if found is None:
        return None
    chains = [found[-1][-1][None, :], *(found[last - k + 1][::-1] for k in range(1, last + 1))]
    return chains if backs_off else [*chains, chains[-1][::-1]]


def _drawn_out(base_pose: Pose2D, point: np.ndarray, size: np.ndarray, surface_z: float | None
               ) -> np.ndarray | None:
    """The way an object whose top is at ``point`` is drawn out of storage (`_toward` the base)
    where it stands `IN_STORAGE_M` or more above the surface; None on the surface, where a lift
    raised by what stands before it let a route taken unchecked reach over a box just put down
    (recursive 1059 of tuning-wide)."""
    if surface_z is not None and point[2] - size[2] <= surface_z + IN_STORAGE_M:
        return None
    return _toward(base_pose, point)


def _toward(base_pose: Pose2D, point: np.ndarray) -> np.ndarray:
    """The level unit vector from ``point`` towards the base."""
    toward = np.array([*(np.asarray(base_pose[:2], dtype=float) - point[:2]), 0.0])
    return toward / max(float(np.linalg.norm(toward)), 1e-9)


@dataclass(frozen=True)
class _Way:
    """One grasp of the object to one place: the grasp, the TCP at the grasp and at the release,
    and whether a board stands close over either, lifted `lift_m` (`skills.arm.headroom.confined`)."""

    grasp_way: ObjectGrasp
    grasp: np.ndarray
    release: np.ndarray
    confined_here: bool
    confined_there: bool


def _ways(grasps: list[ObjectGrasp], top: np.ndarray, place: np.ndarray, size: np.ndarray, lift_m: float,
          clearance_m: float, keep_off: np.ndarray | None) -> list[_Way]:
    """Each grasp's way to ``place``, those whose hand touches fewer of ``keep_off`` coming straight
    down onto the object and onto the place first (stable: else best first)."""
    ways = []
    boarded = [under_a_board(point, size, keep_off, lift_m) for point in (top, place)]
    for way in grasps:
        grasp = pose_at(way.rotation, top + way.offset - way.depth * UP)
        release = pose_at(way.rotation, place + way.offset + (clearance_m - way.depth) * UP)
        here, there = (board or confined(shifted(pose, lift_m * UP), keep_off)
                       for board, pose in zip(boarded, (grasp, release), strict=True))
        ways.append((_touched(grasp, release, lift_m, keep_off), _Way(way, grasp, release, here, there)))
    return [entry for _, entry in sorted(ways, key=lambda pair: pair[0])]


@dataclass(frozen=True)
class _Route:
    """One way to pick: the grasp (``way``, the TCP at ``grasp`` and at ``release``), how high the
    object is lifted, how the hand comes to the pose above it (``approach``: its first stage
    free), and by how much (world offsets; zero for none) the object is drawn out towards the robot
    after the lift (``out``) and brought in from before its place (``inward``): out of the
    cabinet it stood in, into the one it goes back to."""

    way: ObjectGrasp
    grasp: np.ndarray
    release: np.ndarray
    lift: float
    approach: tuple[tuple[str, str, Any], ...]
    out: np.ndarray
    inward: np.ndarray

    @property
    def backs_off(self) -> bool:
        """Whether the hand holds the object's side: it comes onto it and backs off from it level."""
        return self.way.name == SIDE

    @property
    def down(self) -> str:
        if self.backs_off:
            return "in onto the object's side"
        return "down onto the object's top" if self.way.touch else "down onto the object"

    @property
    def back(self) -> str:
        return "back off" if self.backs_off else "back up"

    def stages(self) -> list[tuple[str, str, Any]]:
        """The chain's stages: the approach, down, lift, out, carry, in, lower, back up."""
        above_grasp, above_release = shifted(self.grasp, self.lift * UP), shifted(self.release, self.lift * UP)
        stages = [*self.approach, (self.down, "line", self.grasp), ("lift", "line", above_grasp)]
        if np.any(self.out):
            stages.append(("out", "line", shifted(above_grasp, self.out)))
        stages.append(("carry", "line", shifted(above_release, self.inward)))
        if np.any(self.inward):
            stages.append(("in", "line", above_release))
        back = self.release @ local_pose(z=-APPROACH_M) if self.backs_off else above_release
        return stages + [("lower", "line", self.release), (self.back, "line", back)]

    def build(self, builder: PlanBuilder, named: dict[str, np.ndarray], leaving: Clearance) -> None:
        """The plan's steps from the stages' waypoints (``named`` by stage); the move to the ready
        pose at the end keeps clear of ``leaving``."""
        targets = {what: target for what, _, target in self.stages()}
        first = self.approach[0][0]
        builder.free_move(f"to {first}", named[first][-1])
        for what, _, target in self.approach[1:]:
            builder.move(f"{'down' if first.startswith('high') else 'in'} to {what}", named[what], careful=True,
                         stop_on_contact=True, tcp_target=target)
        builder.grasp(self.way, self.down, named[self.down], self.grasp, "object")
        # The lift begins with the thing on what it stands on, pressed there by the fingertips of a
        # grasp on its top: that contact, a millimetre deep, stopped a box's lift out of a drawer at
        # its first sample (recursive 1050 of tuning-wide). Only a contact it did not begin with,
        # or that one pressed deeper, stops the lift; any contact stops the moves after it.
        builder.move("lift", named["lift"], careful=True, tcp_target=targets["lift"])
        builder.steps[-1] = replace(builder.steps[-1], stop_on_new_contact=True)
        for what in ("out", "carry", "in"):  # what it carries meeting a door or drawer stops it
            if what in named:
                builder.move(what, named[what], careful=what != "carry", stop_on_contact=True,
                             tcp_target=targets[what])
        builder.move("lower", named["lower"], careful=True, tcp_target=self.release, touch="support")
        builder.gripper("open", "put the object down")
        builder.move(self.back, named[self.back], careful=True, tcp_target=targets[self.back])
        builder.free_move("to ready", builder.arm.ready, via_ready=False, clearance=leaving)


def _clear_routes(ways: list[_Way], lift_m: float, size: np.ndarray, keep_off: np.ndarray | None,
                  toward: np.ndarray, to_place: np.ndarray, room: float = np.inf, over: float = 0.0
                  ) -> list[_Route]:
    """The routes to seek a chain clear all the way on, likeliest first, `CLEAR_ROUTES` at most.

    In the open, the best `CLEAR_GRASPS` grasps, lifted `lift_m` and then, where what stands in
    the way across needs it (``over``, up to `HIGHEST_LIFT_M`), higher, from high above, directly
    or from before the pose above; carried straight across, or, after every straight route, round
    by the robot's side (`_detours`).
    Where a board stands close over the object or its place (`skills.arm.headroom.confined`: a
    box inside a cabinet) a hand straight down has no room for its wrist: the top's near edge is
    grasped, the hand leaning back towards the robot, the steepest first, or the side that faces
    the robot, the hand level, first where the board leaves less than `LEANING_ROOM_M` over the
    lift (``room``: the lowest board over the object's top or its place,
    `skills.arm.headroom.headroom`); the object is lifted only as high as clears what it covers
    first (`_lifts`); the hand comes in directly or from before the
    pose above it (onto a side: from before it, `_side_approaches`); and the object is drawn
    straight out of the storage before the carry, or brought straight into it after, by each of
    `BEFORE_M` (held by its side: square to that side)."""
    routes = []
    open_ways = [entry for entry in ways if entry.grasp_way.name not in (EDGE, SIDE)][:CLEAR_GRASPS]
    edge_ways = sorted((entry for entry in ways if entry.grasp_way.name == EDGE),
                       key=lambda entry: -float(entry.grasp_way.rotation[2, 2]))  # the steepest lean first
    side_ways = [entry for entry in ways if entry.grasp_way.name == SIDE]
    tight = room < _lifts(lift_m, size)[-1] + LEANING_ROOM_M
    for entry in [*(side_ways + edge_ways if tight else edge_ways + side_ways), *open_ways]:
        way, grasp, release = entry.grasp_way, entry.grasp, entry.release
        here, there = entry.confined_here, entry.confined_there
        if way.name in (EDGE, SIDE) and not (here or there):
            continue
        out_along, in_along = (-way.rotation[:, 2], -way.rotation[:, 2]) if way.name == SIDE else (toward, to_place)
        for lift in _lifts(lift_m, size)[::-1] if here or there else _open_lifts(lift_m, over):
            if way.name == SIDE:
                approaches = _side_approaches(grasp)
            else:
                approaches = _approaches(shifted(grasp, lift * UP), keep_off, toward, True)
            for approach in approaches:
                for out, inward in _detours(here, there):
                    routes.append(_Route(way, grasp, release, lift, tuple(approach), out * out_along,
                                         inward * in_along))
    def in_storage(route: _Route) -> bool:  # open routes first, stable: else in the order built
        return bool(np.any(route.out) or np.any(route.inward) or route.way.name in (EDGE, SIDE))

    return sorted(routes, key=in_storage)[:CLEAR_ROUTES]


def _detours(here: bool, there: bool) -> list[tuple[float, float]]:
    """How far (m) to draw the object out towards the robot after the lift, and to bring it in from
    before its place: out of and into storage by each of `BEFORE_M`; in the open, straight across
    first and then round by the robot's side (`DETOUR_M` out and in), clear of a cabinet that
    stands between where a wide box is lifted and where it goes down beside it."""
    if not (here or there):
        return [(0.0, 0.0), (DETOUR_M, DETOUR_M)]
    outs, ins = (BEFORE_M[:2] if here else (0.0,)), (BEFORE_M[:2] if there else (0.0,))
    return [(out, inward) for out in outs for inward in ins]


def _plain_routes(ways: list[_Way], lift_m: float, keep_off: np.ndarray | None) -> list[_Route]:
    """The routes as they were before clear chains were sought: every grasp, lifted `lift_m`, from
    high above where that is open, else directly; none where a board stands close over the grasp or
    the release (`skills.arm.headroom.confined`). There an unchecked route wrecks the storage: a
    box lifted unchecked out of an open drawer pushed both of the chest's drawers 10 and 27 cm in
    past their end stops (recursive 1018 of tuning-wide); a pick that fails there leaves the storage as it was."""
    none = np.zeros(3)
    routes = []
    for entry in ways:
        if entry.confined_here or entry.confined_there or entry.grasp_way.name == SIDE:
            continue
        above = shifted(entry.grasp, lift_m * UP)
        for approach in _approaches(above, keep_off, none, before=False):
            routes.append(_Route(entry.grasp_way, entry.grasp, entry.release, lift_m, tuple(approach), none, none))
    return routes


def _lifts(lift_m: float, size: np.ndarray) -> list[float]:
    """How high above its place an object may be lifted, the usual first: then only as high as
    clears what it covers (its own height: a box over a smaller one), for a board close above it."""
    low = max(float(size[2]) + LIFT_SPARE_M, LOW_LIFT_M)
    return [lift_m] if low >= lift_m else [lift_m, low]


def _open_lifts(lift_m: float, over: float) -> list[float]:
    """How high above its place an object carried in the open may be lifted: the usual first, then
    ``over`` what stands in the way across where that is higher, and not above `HIGHEST_LIFT_M`."""
    return [lift_m, over] if lift_m < over <= HIGHEST_LIFT_M else [lift_m]


def _approaches(above: np.ndarray, keep_off: np.ndarray | None, toward: np.ndarray, before: bool
                ) -> list[list[tuple[str, str, Any]]]:
    """Ways for the hand to the pose ``above`` the object, to try in turn: from `HIGH_ABOVE_M` higher,
    straight down, where `_open_above`; directly; and, with ``before``, from in front of it
    (``toward`` the robot, `BEFORE_M`), straight in: through the opening of a cabinet, past what
    stands beside it."""
    approaches = []
    if _open_above(above, keep_off):
        approaches.append([("high above the object", "free", shifted(above, HIGH_ABOVE_M * UP)),
                           ("above the object", "line", above)])
    approaches.append([("above the object", "free", above)])
    if before:
        approaches.append([("before the object", "free", shifted(above, BEFORE_M[1] * toward)),
                           ("above the object", "line", above)])
    return approaches


def _side_approaches(grasp: np.ndarray) -> list[list[tuple[str, str, Any]]]:
    """Ways for a hand at an object's side to the pose before it (`APPROACH_M` back along its
    level axis): directly, and from as far again further back, straight in: through the opening
    of a cabinet, under its board."""
    before = grasp @ local_pose(z=-APPROACH_M)
    return [[("before the object's side", "free", before)],
            [("well before the object's side", "free", grasp @ local_pose(z=-2 * APPROACH_M)),
             ("before the object's side", "line", before)]]


def _open_above(pose: np.ndarray, keep_off: np.ndarray | None) -> bool:
    """Whether the hand may come down onto ``pose`` from `HIGH_ABOVE_M` higher: none of ``keep_off``
    stands in its way up there (the board over a box inside a cabinet, a door standing open over
    it: the hand pushed the door on its way in)."""
    return not any(hand_touches(shifted(pose, height * UP), keep_off)
                   for height in np.arange(0.02, HIGH_ABOVE_M + 1e-9, 0.02))


def _touched(grasp: np.ndarray, release: np.ndarray, lift_m: float, keep_off: np.ndarray | None) -> int:
    """How many of ``keep_off`` the hand would touch coming straight down onto the grasp and the
    release (checked every 2 cm from ``lift_m`` above)."""
    if keep_off is None or not len(keep_off):
        return 0
    return sum(hand_touches(shifted(pose, height * UP), keep_off)
               for pose in (grasp, release) for height in np.arange(0.0, lift_m + 1e-9, 0.02))
