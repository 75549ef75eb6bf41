"""Plans for picking an object away and back: top-down, or, under a board, by its side.

Above the object (in from higher up, straight down: `skills.arm.pick_routes.HIGH_ABOVE_M`), down
onto its top (the fingers closing across the line of sight from the robot where the object fits
that way, since perception places things worst along it, unless the hand would touch less of what
stands near coming down another way; an object wider than the opening is held by the closed
fingertips brought down onto its top until they touch, `skills.arm.grasps.object_grasps`), close,
lift, carry at height, lower until the object stands a little above where it should, or until it
meets what it is put on first (a top a little higher than the memory had it holds the arm back
without the arm touching anything: the world puts a released object down onto whatever is under
it), open, back up, ready. Under a board close over it (a box in a cabinet), the hand takes its
top's near edge leaning back towards the robot, or, where the board leaves too little room for that
wrist, the side facing the robot, the hand level (`skills.arm.grasps.side_grasps`); the object is
drawn straight out of the storage, and the hand backs off it level after letting go. What stands
over and around the object, and the room it leaves, is `skills.arm.headroom`'s; the routes a chain
of postures is sought along, `skills.arm.pick_routes`'.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.clearance import Carried, Clearance, box_points
from skills.arm.frames import base_transform
from skills.arm.grasp_lines import searched
from skills.arm.grasps import OPEN_EDGE_INSET_M, UP, ObjectGrasp, object_grasps, side_grasps
from skills.arm.headroom import LIFT_M, headroom, over_the_rim, over_the_way, too_low_to_lift
from skills.arm.ik_search import IKSearch, PostureCheck
from skills.arm.pick_routes import (LEANING_ROOM_M, Route, Way, clear_routes, edge_routes_in_the_open, lifts,
                                    plain_routes, ways)
from skills.arm.plan_builder import PlanBuilder
from skills.arm.skill_plan import SkillPlan, SkillPlanError, best_failure, checked_vector

#: How far (m) open fingers must clear an object on either side to close around it; else they rest
#: on its top. The memory places things to within its 1 cm voxels: a 7 cm carton in the 8 cm
#: opening, 5 mm either side, was missed by a finger landing on its top.
STRADDLE_CLEARANCE_M = 0.008
#: The stages of a pick in which the hand carries the object, and those on the way to it.
_CARRYING = frozenset({"lift", "out", "carry", "in", "lower"})
_COMING = frozenset({"high above the object", "above the object", "before the object",
                     "well before the object's side", "before the object's side"})
#: The stages in which the object is lifted clear of where it stood and of where it goes.
_LIFTED = frozenset({"out", "carry", "in"})
#: How far over the surface (m) an object's bottom stands where it stands in storage, drawn out
#: over the front of what it stands in (`skills.arm.headroom.over_the_rim`'s ``out``).
IN_STORAGE_M = 0.03


def plan_pick(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, object_point: Sequence[float],
              extent: Sequence[float], place_point: Sequence[float], *, skill: str = "pick_away",
              surface_z: float | None = None, lift_m: float = LIFT_M, clearance_m: float = 0.015,
              grasp_depth_m: float | None = None, keep_off: np.ndarray | None = None,
              grasp_first: ObjectGrasp | None = None, near_edge: bool = False) -> SkillPlan:
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
        near_edge: after every other route, seek those of the grasps of the near edge of a top in
            the open (`edge_routes_in_the_open`), the fingertips `OPEN_EDGE_INSET_M` inside it:
            for a top beyond the hand's reach from above, where no other stand reaches it
            (`skills.robot_picks.Picks.pick_away` asks last). Held so, a box is less sure in the
            hand than by any other grasp: sought from the front before the other sides were, it
            took two picks away from the sides that lifted them and closed on nothing.

    Returns:
        The plan; ``info["grasp"]`` says whether the fingers close around the object or their tips
        rest on its top (``info["grasp_way"]``: the grasp itself), ``info["place_point"]`` where it goes.

    Raises:
        SkillPlanError: a bad argument, no room over the object to lift it off what it may cover
            (`skills.arm.headroom.too_low_to_lift`), or no grasp reaches along the whole chain.
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
    if too_low_to_lift(top, size, keep_off, least := lifts(lift_m, size)[-1]):
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
    overs = [over_the_way(top, place, size, keep_off) for place in places]

    def sought(choices: list[ObjectGrasp]) -> tuple[list[list[Way]], list[tuple[Route, bool]]]:
        ways_to = [ways(choices, top, place, size, lift_m, clearance_m, keep_off) for place in places]
        return ways_to, [(route, True) for place, there, over in zip(places, ways_to, overs, strict=True)
                         for route in clear_routes(there, lift_m, size, keep_off, toward, _toward(base_pose, place),
                                                   room, over)]

    # A chain clear of everything all the way, to each place in turn (a few dozen routes at most
    # each, the likeliest first), by ``grasp_first`` before any other; else, as without such
    # checks, to the first place, the first grasp that reaches at all, unless it is confined
    # (`plain_routes`) or carries the object into what stands near (`_carried_into`).
    first = [] if grasp_first is None else [(route, clear) for route, clear in sought([grasp_first])[1]
                                             if grasp_first.touch or np.any(route.inward) or np.any(route.out)]
    ways_to, routes = sought(grasps)
    routes = [*first, *routes, *((route, False) for route in plain_routes(ways_to[0], lift_m, keep_off))]
    if near_edge:  # last, where asked: the near edge of a top beyond the hand's reach from above
        open_edges = object_grasps(size, top, base_pose, arm.gripper_opening - 2 * STRADDLE_CLEARANCE_M, depth,
                                   edge_inset_m=OPEN_EDGE_INSET_M)
        routes += [(route, True) for place in places for route in edge_routes_in_the_open(
            ways(open_edges, top, place, size, lift_m, clearance_m, keep_off), lift_m, size, keep_off, toward,
            _toward(base_pose, place), over_the_way(top, place, size, keep_off))]
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
        stages: the route's stages (`Route.stages`): a free one, lines, and the back-up last.
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
