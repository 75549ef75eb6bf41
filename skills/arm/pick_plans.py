"""Plans for picking an object away and back: top-down.

Above the object (in from higher up, straight down: `HIGH_ABOVE_M`), down onto its top (the fingers closing across the line of sight from the robot
where the object fits that way, since perception places things worst along it, unless the hand
would touch less of what stands near coming down another way; an object wider
than the opening is held by the closed fingertips brought down onto its top until they touch,
`skills.arm.grasps.object_grasps`), close, lift, carry at height, lower until the object stands a
little above where it should, or until it meets what it is put on first (a top a little higher
than the memory had it holds the arm back without the arm touching anything: the world puts a
released object down onto whatever is under it), open, back up, ready.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.clearance import Carried, Clearance, box_points
from skills.arm.frames import base_transform, pose_at, shifted
from skills.arm.grasp_lines import searched
from skills.arm.grasps import UP, hand_touches, object_grasps
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
_CARRYING = frozenset({"lift", "carry", "lower"})
_COMING = frozenset({"high above the object", "above the object"})


def plan_pick(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, object_point: Sequence[float],
              extent: Sequence[float], place_point: Sequence[float], *, skill: str = "pick_away",
              surface_z: float | None = None, lift_m: float = 0.15, clearance_m: float = 0.015,
              grasp_depth_m: float | None = None, keep_off: np.ndarray | None = None) -> SkillPlan:
    """Pick an object and put it down elsewhere (see the module doc).

    Args:
        arm: the arm planned for.
        q: where the arm is.
        base_pose: where the base stands.
        object_point: the object's top grasp point (world).
        extent: its box (dx, dy, dz).
        place_point: where that point should end, less ``clearance_m``.
        skill: the plan's name.
        surface_z: the table's top, which free moves keep the hand above.
        lift_m: how high above the grasp and the release the object is carried.
        clearance_m: how far above ``place_point`` the object is let go.
        grasp_depth_m: how far below its top the fingers close around it (default: from its height).
        keep_off: (N, 3) points of what stands near, neither the object nor what it stands on:
            the grasps whose hand would touch fewer of them, coming down onto the object and onto
            the place, are tried first.

    Returns:
        The plan; ``info["grasp"]`` says whether the fingers close around the object or their tips
        rest on its top.

    Raises:
        SkillPlanError: a bad argument, or no grasp reaches along the whole chain.
    """
    top = checked_vector(object_point, "object_point")
    place = checked_vector(place_point, "place_point")
    size = checked_vector(extent, "extent")
    if np.any(size <= 0):
        raise SkillPlanError(f"pick: extent {np.round(size, 3).tolist()} must be positive")
    depth = grasp_depth_m if grasp_depth_m is not None else min(0.025, max(0.005, size[2] / 2 - 0.005))
    here = arm.start_configuration(q)
    ik = IKSearch(arm, here, base_pose)
    near = np.zeros((0, 3)) if keep_off is None else np.asarray(keep_off, dtype=float).reshape(-1, 3)
    clearance = Clearance(arm, base_transform(base_pose), surface_z, near)
    # On the way to it, the object is in the way too: a finger swept across a carton's top.
    around = Clearance(arm, base_transform(base_pose), surface_z,
                       np.vstack([near, box_points(top - size[2] / 2 * UP, size)]))
    builder = PlanBuilder(arm, here, base_pose, surface_z, around)
    failures: list[str] = []
    ways = []
    for way in object_grasps(size, top, base_pose, arm.gripper_opening - 2 * STRADDLE_CLEARANCE_M, depth):
        grasp = pose_at(way.rotation, top + way.offset - way.depth * UP)
        release = pose_at(way.rotation, place + way.offset + (clearance_m - way.depth) * UP)
        ways.append((way, grasp, release, _touched(grasp, release, lift_m, keep_off)))
    ways.sort(key=lambda entry: entry[3])  # clear of the neighbours first; stable: else best first
    for way, grasp, release, _ in ways:
        above_grasp, above_release = shifted(grasp, lift_m * UP), shifted(release, lift_m * UP)
        down = "down onto the object's top" if way.touch else "down onto the object"
        rest = [(down, "line", grasp), ("lift", "line", above_grasp), ("carry", "line", above_release),
                ("lower", "line", release), ("back up", "line", above_release)]
        carried = Carried.held_at(grasp, top - size[2] / 2 * UP, size)

        def check(what: str, posture: np.ndarray) -> str | None:
            if what in _COMING:
                return around.problem(posture, hand=True)
            return clearance.problem(posture, carried if what in _CARRYING else None)

        try:
            chains = _chain_from_above(ik, above_grasp, rest, keep_off, check)
            come, chain = chains[:-len(rest)], chains[-len(rest):]
            descent = searched(ik, chain[0], grasp, down) if way.touch else chain[0]
        except SkillPlanError as error:
            failures.append(str(error))
            continue
        builder.free_move("to above the object" if len(come) == 1 else "to high above the object", come[0][-1])
        if len(come) == 2:
            builder.move("down to above the object", come[1], careful=True, stop_on_contact=True,
                         tcp_target=above_grasp)
        builder.grasp(way, down, descent, grasp, "object")
        builder.move("lift", chain[1], careful=True, tcp_target=above_grasp)
        builder.move("carry", chain[2], careful=False, tcp_target=above_release)
        builder.move("lower", chain[3], careful=True, tcp_target=release, touch="support")
        builder.gripper("open", "put the object down")
        builder.move("back up", chain[4], careful=True, tcp_target=above_release)
        builder.free_move("to ready", arm.ready, via_ready=False)
        info = {"grasp_pose": grasp, "release_pose": release, "object_point": top, "place_point": place,
                "grasp_depth_m": way.depth, "grasp": way.name}
        return builder.finish(skill, info, ik)
    raise SkillPlanError(best_failure(failures, "pick"))


def _chain_from_above(ik: IKSearch, above: np.ndarray, rest: list[tuple[str, str, Any]],
                      keep_off: np.ndarray | None, check: PostureCheck) -> list[np.ndarray]:
    """The pick's chain, coming to the pose ``above`` the object from `HIGH_ABOVE_M` higher,
    straight down, where `_open_above`; else, or where that is out of reach, straight to it. Each
    tries the arm's postures for the clear one (`IKSearch.chain`)."""
    if _open_above(above, keep_off):
        try:
            return ik.chain([("high above the object", "free", shifted(above, HIGH_ABOVE_M * UP)),
                             ("above the object", "line", above), *rest], check)
        except SkillPlanError:
            pass  # out of reach up there: as before
    return ik.chain([("above the object", "free", above), *rest], check)


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
