"""The routes a pick is sought on, likeliest first: which grasp, how high the object is lifted, how
the hand comes to it, and whether the object is drawn out of storage or brought into it
(`skills.arm.pick_plans.plan_pick` seeks a chain of postures clear all the way along each in turn).
What stands over and around the object is `skills.arm.headroom`'s.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from skills.arm.clearance import Clearance
from skills.arm.frames import pose_at, shifted
from skills.arm.grasp_lines import APPROACH_M
from skills.arm.grasps import UP, ObjectGrasp, hand_touches, local_pose
from skills.arm.headroom import LIFT_SPARE_M, confined, under_a_board
from skills.arm.plan_builder import PlanBuilder

#: The hand comes to the pose above an object from this much (m) higher, straight down, where
#: nothing remembered stands up there: a free move's joint path to that pose swept a finger across
#: the top of a 20 cm milk carton put down near the base, which stopped the pick back (occlusion
#: 1000 of tuning-wide).
HIGH_ABOVE_M = 0.12
#: The grasps of an object's top near its edge and of its side, tried only under a board.
EDGE, SIDE = "fingertips-on-near-edge", "fingertips-on-near-side"
#: How much room (m) over an object's top a hand on its near edge needs for its wrist, leaning back
#: 65° (`skills.arm.grasps.EDGE_PITCHES`), the steepest tried; under a board lower than that over
#: the lift, the grasps of its side are tried first (`clear_routes`).
LEANING_ROOM_M = 0.19
#: How far before the pose above the object (towards the robot, m) the hand may come in from.
BEFORE_M = (0.15, 0.3, 0.45)
#: A low lift clears the object's own height by `skills.arm.headroom.LIFT_SPARE_M`, and is never
#: lower than this (m) (`lifts`).
LOW_LIFT_M = 0.05
#: Grasps of the middle of an object tried for a chain clear all the way, best first, before the
#: grasps of its near edge and settling for one that merely reaches; routes tried so at the most.
CLEAR_GRASPS, CLEAR_ROUTES = 4, 48
#: How far (m) a carry in the open goes round by the robot's side when straight across is not clear.
DETOUR_M = 0.25
#: The highest (m) a carry in the open is raised to pass over what stands in its way
#: (`skills.arm.headroom.over_the_way`); what stands higher is gone round (`DETOUR_M`).
HIGHEST_LIFT_M = 0.3


@dataclass(frozen=True)
class Way:
    """One grasp of the object to one place: the grasp, the TCP at the grasp and at the release,
    whether a board stands close over either, lifted `lift_m` (`skills.arm.headroom.confined`), and
    how far above its place the object is let go (``rise``, m)."""

    grasp_way: ObjectGrasp
    grasp: np.ndarray
    release: np.ndarray
    confined_here: bool
    confined_there: bool
    rise: float


def ways(grasps: list[ObjectGrasp], top: np.ndarray, place: np.ndarray, size: np.ndarray, lift_m: float,
         clearance_m: float, keep_off: np.ndarray | None) -> list[Way]:
    """Each grasp's way to ``place``, those whose hand touches fewer of ``keep_off`` coming straight
    down onto the object and onto the place first (stable: else best first).

    Args:
        grasps: the grasps of the object.
        top: the middle of its top (world).
        place: where that point goes.
        size: its box (dx, dy, dz).
        lift_m: how high it is lifted, where a board close over the hand counts.
        clearance_m: how far above ``place`` it is let go.
        keep_off: (N, 3) points of what stands near, or None.

    Returns:
        One way per grasp.
    """
    found = []
    boarded = [under_a_board(point, size, keep_off, lift_m) for point in (top, place)]
    for way in grasps:
        grasp = pose_at(way.rotation, top + way.offset - way.depth * UP)
        release = pose_at(way.rotation, place + way.offset + (clearance_m - way.depth) * UP)
        here, there = (board or confined(shifted(pose, lift_m * UP), keep_off)
                       for board, pose in zip(boarded, (grasp, release), strict=True))
        found.append((_touched(grasp, release, lift_m, keep_off), Way(way, grasp, release, here, there, clearance_m)))
    return [entry for _, entry in sorted(found, key=lambda pair: pair[0])]


@dataclass(frozen=True)
class Route:
    """One way to pick: the grasp (``way``, the TCP at ``grasp`` and at ``release``), how high the
    object is lifted, how the hand comes to the pose above it (``approach``: its first stage
    free), by how much (world offsets; zero for none) the object is drawn out towards the robot
    after the lift (``out``) and brought in from before its place (``inward``): out of the
    cabinet it stood in, into the one it goes back to; and how far above its place it is let go
    (``rise``, `Way.rise`)."""

    way: ObjectGrasp
    grasp: np.ndarray
    release: np.ndarray
    lift: float
    approach: tuple[tuple[str, str, Any], ...]
    out: np.ndarray
    inward: np.ndarray
    rise: float

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
        """The chain's stages: the approach, down, lift, out, carry, in, lower, back up. Brought into
        storage (``inward``), the object is carried ``lift`` above its place, as high as it was
        lifted where it stood, not above the release (``rise`` higher): lowered from that much
        higher into the cabinet it was lifted out of, a box 10 cm tall under a board 12.6 cm over
        it came 3 mm short of the board with the arm's margin, and no route put it back (recursive
        1173 of tuning-wide). In the open it is carried ``lift`` above the release.

        Returns:
            (what, "free" or "line", the TCP's world target) of each, in order.
        """
        above_grasp = shifted(self.grasp, self.lift * UP)
        above_release = shifted(self.release, (self.lift - (self.rise if np.any(self.inward) else 0.0)) * UP)
        stages = [*self.approach, (self.down, "line", self.grasp), ("lift", "line", above_grasp)]
        if np.any(self.out):
            stages.append(("out", "line", shifted(above_grasp, self.out)))
        stages.append(("carry", "line", shifted(above_release, self.inward)))
        if np.any(self.inward):
            stages.append(("in", "line", above_release))
        back = self.release @ local_pose(z=-APPROACH_M) if self.backs_off else above_release
        return stages + [("lower", "line", self.release), (self.back, "line", back)]

    def build(self, builder: PlanBuilder, named: dict[str, np.ndarray], leaving: Clearance) -> None:
        """The plan's steps from the stages' waypoints.

        Args:
            builder: the plan being built.
            named: each stage's waypoints, by its name (`stages`).
            leaving: what the move to the ready pose at the end keeps clear of.
        """
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


def clear_routes(choices: list[Way], lift_m: float, size: np.ndarray, keep_off: np.ndarray | None,
                 toward: np.ndarray, to_place: np.ndarray, room: float = np.inf, over: float = 0.0
                 ) -> list[Route]:
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
    first (`lifts`); the hand comes in directly or from before the
    pose above it (onto a side: from before it, `_side_approaches`); and the object is drawn
    straight out of the storage before the carry, or brought straight into it after, by each of
    `BEFORE_M` (held by its side: square to that side).

    Args:
        choices: the grasps' ways to one place (`ways`).
        lift_m: the usual lift (m).
        size: the object's box (dx, dy, dz).
        keep_off: (N, 3) points of what stands near, or None.
        toward: the level unit vector from the object towards the base.
        to_place: the same from its place.
        room: how far over the object's top or its place the lowest board stands (m).
        over: how high a carry in the open must be lifted to clear what stands in its way
            (`skills.arm.headroom.over_the_way`).

    Returns:
        The routes, open ones first.
    """
    routes = []
    open_ways = [entry for entry in choices if entry.grasp_way.name not in (EDGE, SIDE)][:CLEAR_GRASPS]
    edge_ways = sorted((entry for entry in choices if entry.grasp_way.name == EDGE),
                       key=lambda entry: -float(entry.grasp_way.rotation[2, 2]))  # the steepest lean first
    side_ways = [entry for entry in choices if entry.grasp_way.name == SIDE]
    tight = room < lifts(lift_m, size)[-1] + LEANING_ROOM_M
    for entry in [*(side_ways + edge_ways if tight else edge_ways + side_ways), *open_ways]:
        if entry.grasp_way.name in (EDGE, SIDE) and not (entry.confined_here or entry.confined_there):
            continue
        routes += _routes_of(entry, lift_m, size, keep_off, toward, to_place, over)

    def in_storage(route: Route) -> bool:  # open routes first, stable: else in the order built
        return bool(np.any(route.out) or np.any(route.inward) or route.way.name in (EDGE, SIDE))

    return sorted(routes, key=in_storage)[:CLEAR_ROUTES]


def edge_routes_in_the_open(choices: list[Way], lift_m: float, size: np.ndarray, keep_off: np.ndarray | None,
                            toward: np.ndarray, to_place: np.ndarray, over: float = 0.0) -> list[Route]:
    """The routes of the grasps of an object's near edge, the steepest lean first, where no board
    stands close over it or its place: sought after every other route, checked or taken
    unchecked, has failed. From above, the hand reaches a top about 0.85 m from the base's axis; a
    nest of boxes on the table 1.0 m out beside the storage at its back was out of its reach from
    the front, and from the back no free place was within reach (recursive 1182 of tuning-wide);
    its near edge, 0.1 m nearer, is reached leaning back.

    Args:
        choices: the grasps' ways to one place (`ways`); those of the near edge count.
        lift_m: the usual lift (m).
        size: the object's box (dx, dy, dz).
        keep_off: (N, 3) points of what stands near, or None.
        toward: the level unit vector from the object towards the base.
        to_place: the same from its place.
        over: as for `clear_routes`.

    Returns:
        The routes, `CLEAR_ROUTES` at most.
    """
    edges = sorted((entry for entry in choices if entry.grasp_way.name == EDGE
                    and not (entry.confined_here or entry.confined_there)),
                   key=lambda entry: -float(entry.grasp_way.rotation[2, 2]))
    return [route for entry in edges for route in _routes_of(entry, lift_m, size, keep_off, toward, to_place, over)
            ][:CLEAR_ROUTES]


def _routes_of(entry: Way, lift_m: float, size: np.ndarray, keep_off: np.ndarray | None, toward: np.ndarray,
               to_place: np.ndarray, over: float) -> list[Route]:
    """One way's routes, by each lift (`lifts` where a board stands close over either end, else
    `_open_lifts`), each approach and each detour (`clear_routes`)."""
    way, grasp, release = entry.grasp_way, entry.grasp, entry.release
    here, there = entry.confined_here, entry.confined_there
    out_along, in_along = (-way.rotation[:, 2], -way.rotation[:, 2]) if way.name == SIDE else (toward, to_place)
    routes = []
    for lift in lifts(lift_m, size)[::-1] if here or there else _open_lifts(lift_m, over):
        if way.name == SIDE:
            approaches = _side_approaches(grasp)
        else:
            approaches = _approaches(shifted(grasp, lift * UP), keep_off, toward, True)
        for approach in approaches:
            for out, inward in _detours(here, there):
                routes.append(Route(way, grasp, release, lift, tuple(approach), out * out_along, inward * in_along,
                                    entry.rise))
    return routes


def _detours(here: bool, there: bool) -> list[tuple[float, float]]:
    """How far (m) to draw the object out towards the robot after the lift, and to bring it in from
    before its place: out of and into storage by each of `BEFORE_M`; in the open, straight across
    first and then round by the robot's side (`DETOUR_M` out and in), clear of a cabinet that
    stands between where a wide box is lifted and where it goes down beside it."""
    if not (here or there):
        return [(0.0, 0.0), (DETOUR_M, DETOUR_M)]
    outs, ins = (BEFORE_M[:2] if here else (0.0,)), (BEFORE_M[:2] if there else (0.0,))
    return [(out, inward) for out in outs for inward in ins]


def plain_routes(choices: list[Way], lift_m: float, keep_off: np.ndarray | None) -> list[Route]:
    """The routes as they were before clear chains were sought: every grasp, lifted `lift_m`, from
    high above where that is open, else directly; none where a board stands close over the grasp or
    the release (`skills.arm.headroom.confined`). There an unchecked route wrecks the storage: a
    box lifted unchecked out of an open drawer pushed both of the chest's drawers 10 and 27 cm in
    past their end stops (recursive 1018 of tuning-wide); a pick that fails there leaves the storage as it was.

    Args:
        choices: the grasps' ways to one place (`ways`).
        lift_m: the lift (m).
        keep_off: (N, 3) points of what stands near, or None.

    Returns:
        The routes, to be taken unchecked.
    """
    none = np.zeros(3)
    routes = []
    for entry in choices:
        if entry.confined_here or entry.confined_there or entry.grasp_way.name == SIDE:
            continue
        above = shifted(entry.grasp, lift_m * UP)
        for approach in _approaches(above, keep_off, none, before=False):
            routes.append(Route(entry.grasp_way, entry.grasp, entry.release, lift_m, tuple(approach), none, none,
                                entry.rise))
    return routes


def lifts(lift_m: float, size: np.ndarray) -> list[float]:
    """How high above its place an object may be lifted, the usual first: then only as high as
    clears what it covers (its own height: a box over a smaller one), for a board close above it.

    Args:
        lift_m: the usual lift (m).
        size: the object's box (dx, dy, dz).

    Returns:
        The lifts, the lowest last.
    """
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
