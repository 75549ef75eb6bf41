"""A straight drive with the arm out that keeps the hand off the doors and drawers the robot left open.

The base drives with the arm where the last skill left it, ahead of the base, and the world stops
the drive on the first touch. A door the robot opened swings out towards it, and a base sliding
along the table's edge to its next stand carries the hand into that door (the base then could not
reach a box or drawer beside it); folding the arm in first would sweep it through the door. The
drive knows where those parts stand now (the memory's points, carried by the skills that moved
them): when the hand's way crosses them, the base backs straight away from the table until the hand
passes behind them, slides there, and comes forward to its stand at the end. Where the arm, as it
is, would touch a part once the base stands there (the robot coming back to the stand of a door it
opened, its arm out as a look elsewhere left it: recursive 1008, drawer-door 1011 of tuning-wide),
it is folded in before the base comes forward, where the fold keeps clear of the parts
(`fold_place`): a fold beside the door swings the arm through it (drawer-door 1006).

Pure: the arm's and the parts' points in, the path out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.clearance import Clearance
from skills.arm.fold_plans import plan_stow
from skills.arm.frames import base_transform
from skills.arm.skill_plan import SkillPlanError

#: How far (m) the hand keeps from an open part's points on the way, across and along.
CLEAR_M = 0.05
#: The spacing (m) of the base positions the hand's way is checked at.
STEP_M = 0.02
#: How much further back (m) than a way round the parts the arm may be folded in, nearest first.
FOLD_BACK_M = (0.0, 0.15, 0.3)


def clear_path(here: Pose2D, there: Pose2D, hand: np.ndarray, standing_open: Sequence[np.ndarray],
               clear_m: float = CLEAR_M) -> list[tuple[float, float]]:
    """The (x, y) waypoints of a drive from ``here`` to ``there`` whose hand stays off ``standing_open``.

    The hand keeps its place relative to the base (the base only slides; it turns at the end); a
    part's point is in its way when, at some base position along the straight line, it lies within
    ``clear_m`` of the hand's box (in the base's frame, and in height). Then the base first backs
    straight away along its heading, far enough that every such point stands ``clear_m`` ahead of
    the hand, drives along, and comes forward onto ``there``.

    Args:
        here: where the base stands (its heading is kept on the way).
        there: where it is to stand.
        hand: (N, 3) points of the hand (and what it holds), world frame, where they are now.
        standing_open: point sets (each (M, 3)) of the parts this robot opened that still stand open.

    Returns:
        ``[there]`` when the straight way is clear (or there is nothing to keep off), else the backed-off
        start, the backed-off end and ``there``.
    """
    goal = (float(there[0]), float(there[1]))
    points = [np.asarray(p, dtype=float) for p in standing_open if len(p)]
    hand = np.asarray(hand, dtype=float)
    if not points or not len(hand):
        return [goal]
    ahead = np.array([math.cos(here[2]), math.sin(here[2])])
    side = np.array([-ahead[1], ahead[0]])
    start, end = np.asarray(here[:2], dtype=float), np.asarray(there[:2], dtype=float)
    rel = hand[:, :2] - start
    hand_ahead, hand_side = rel @ ahead, rel @ side
    low, high = float(hand[:, 2].min()) - clear_m, float(hand[:, 2].max()) + clear_m
    others = np.vstack(points)
    others = others[(others[:, 2] >= low) & (others[:, 2] <= high)]
    if not len(others):
        return [goal]
    steps = max(1, math.ceil(float(np.linalg.norm(end - start)) / STEP_M))
    back = 0.0
    for t in np.linspace(0.0, 1.0, steps + 1):
        rel_points = others[:, :2] - (start + t * (end - start))
        along, across = rel_points @ ahead, rel_points @ side
        hit = ((across >= hand_side.min() - clear_m) & (across <= hand_side.max() + clear_m)
               & (along >= hand_ahead.min() - clear_m) & (along <= hand_ahead.max() + clear_m))
        if hit.any():
            back = max(back, float(hand_ahead.max() + clear_m - along[hit].min()))
    if back <= 0.0:
        return [goal]
    offset = -back * ahead
    return [tuple(float(v) for v in start + offset), tuple(float(v) for v in end + offset), goal]


def fold_place(arm: ArmModel, q: np.ndarray, path: Sequence[Sequence[float]], there: Pose2D, heading: float,
               standing_open: Sequence[np.ndarray], surface_z: float | None = None) -> list[list[float]] | None:
    """Where on a way round the parts standing open (`clear_path`) to fold the arm in, before the
    base comes forward onto ``there``.

    Args:
        arm: the arm.
        q: its joint positions, as the drive carries them.
        path: `clear_path`'s way: the backed-off start, the backed-off end and ``there``.
        there: where the base is to stand.
        heading: the base's heading on the way.
        standing_open: point sets (each (M, 3)) of the parts this robot opened that still stand open.
        surface_z: the table's top, which the fold keeps the hand above.

    Returns:
        None when the way is straight, or the arm at ``there`` touches none of the parts; else the
        (x, y) way to the first place, the backed-off end or `FOLD_BACK_M` further back in turn,
        from which the fold (`skills.arm.fold_plans.plan_stow`) keeps clear of them all; None when
        none does.
    """
    points = [np.asarray(p, dtype=float) for p in standing_open if len(p)]
    if len(path) != 3 or not points:
        return None
    near = np.vstack(points)
    if Clearance(arm, base_transform(there), None, near).problem(q, hand=True) is None:
        return None
    back = -np.array([math.cos(heading), math.sin(heading)])
    for extra in FOLD_BACK_M:
        way = [[float(v) for v in np.asarray(xy, dtype=float) + extra * back] for xy in path[:2]]
        backed = Pose2D(way[1][0], way[1][1], heading)
        try:
            fold = plan_stow(arm, q, backed, surface_z=surface_z)
        except SkillPlanError:
            continue
        clearance = Clearance(arm, base_transform(backed), None, near)
        if all(clearance.path_problem(step.samples, every=2, hand=True) is None
               for step in fold.steps if step.kind == "move"):
            return way
    return None
