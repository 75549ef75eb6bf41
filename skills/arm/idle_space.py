"""Idle space: free places on a table to put an object down while what it hid is explored (RoboEXP).

Pure: the surface's and every other thing's points in, candidate spots out.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.spatial import cKDTree

from skills.arm.skill_plan import SkillPlanError

#: How far the hand reaches from the TCP across its axis (half its span along the fingers).
HAND_RADIUS_M = 0.11
#: How far below an object's top the hand reaches putting it down (fingers closed around it).
HAND_DIP_M = 0.03


def idle_spot(surface_points: np.ndarray, obstacle_points: Sequence[np.ndarray], radius: float,
              near: Sequence[float], *, margin_m: float = 0.03, grid_m: float = 0.02,
              hand_radius_m: float = HAND_RADIUS_M, height: float | None = None,
              allowed: Callable[[np.ndarray], np.ndarray] | None = None, allowed_means: str = "allowed",
              count: int = 1, apart_m: float = 0.15) -> np.ndarray:
    """A free place on a surface to put an object down: RoboEXP's idle space.

    Points standing above the surface's top (by more than 5 mm) must stay ``margin_m`` beyond the
    object's ``radius`` away in the plane; those that stand up to where the hand works, at the
    object's top (less `HAND_DIP_M`: fingers closed around it reach that far down), must stay
    ``margin_m`` beyond the hand's reach around its TCP (``hand_radius_m``) too. The spot keeps
    ``radius`` + ``margin_m`` inside the top's seen extent.

    Args:
        surface_points: (N, 3) the surface's points (a table's, from the memory); its top is their
            99th height percentile and only points within 1.5 cm of it count.
        obstacle_points: every other thing's points, and the object's own (a spot where it
            stands now is no idle spot).
        radius: the object's footprint radius (m).
        near: the place (x, y) the spot should be nearest to.
        margin_m: room kept around the object or the hand.
        grid_m: the spacing of the candidate places.
        hand_radius_m: how far the hand reaches from the TCP across its axis.
        height: the object's height (m); None: every point standing up counts for the hand.
        allowed: which of an (N, 2) array of places the caller may use (a boolean mask: within
            the arm's reach, say, from `reach_along`: the nearest free place to ``near`` may lie at
            the table's far side, beyond what the arm can carry to); None: all.
        allowed_means: what ``allowed`` asks, for the error when no place is.
        count: how many spots to give, nearest to ``near`` first, each ``apart_m`` from the others:
            where the way to the first is blocked, the next may be clear.
        apart_m: how far apart those spots are at least.

    Returns:
        (x, y, top z) of the candidate nearest to ``near``; with ``count`` above 1, (k, 3) of up
        to ``count`` such spots, the nearest first.

    Raises:
        SkillPlanError: the surface is too small or has too few points, or no place is free.
    """
    points = np.asarray(surface_points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3 or len(points) < 10:
        raise SkillPlanError(f"idle spot: the surface has {len(points)} points, too few to place anything on")
    top = float(np.percentile(points[:, 2], 99))
    flat = points[points[:, 2] >= top - 0.015, :2]
    keep = radius + margin_m
    clear = max(radius, hand_radius_m) + margin_m
    hand_from = top + 0.005 if height is None else top + max(0.005, height - HAND_DIP_M)
    lo, hi = flat.min(axis=0) + keep, flat.max(axis=0) - keep
    if np.any(lo > hi):
        size = np.round(flat.max(axis=0) - flat.min(axis=0), 2).tolist()
        raise SkillPlanError(f"idle spot: the surface's top ({size} m) is too small for a {2 * radius:.2f} m object")
    xs, ys = np.arange(lo[0], hi[0] + 1e-9, grid_m), np.arange(lo[1], hi[1] + 1e-9, grid_m)
    candidates = np.array([(x, y) for x in xs for y in ys])
    on_top, _ = cKDTree(flat).query(candidates, distance_upper_bound=grid_m)
    candidates = candidates[np.isfinite(on_top)]
    standing = np.vstack([np.zeros((0, 3)), *(np.asarray(o, dtype=float) for o in obstacle_points if len(o))])
    for low, need in ((top + 0.005, keep), (hand_from, clear)):
        up = standing[standing[:, 2] > low, :2]
        if len(up) and len(candidates):
            gap, _ = cKDTree(up).query(candidates)
            candidates = candidates[gap >= need]
    if allowed is not None and len(candidates):
        candidates = candidates[np.asarray(allowed(candidates), dtype=bool)]
    if not len(candidates):
        within = "" if allowed is None else f" {allowed_means}"
        raise SkillPlanError(f"idle spot: no free place {2 * clear:.2f} m across on the surface at {top:.3f} m{within}")
    order = np.argsort(np.linalg.norm(candidates - np.asarray(near, dtype=float)[:2], axis=1), kind="stable")
    chosen: list[np.ndarray] = []
    for candidate in candidates[order]:
        if all(float(np.linalg.norm(candidate - other)) >= apart_m for other in chosen):
            chosen.append(candidate)
            if len(chosen) == count:
                break
    spots = np.array([[x, y, top] for x, y in chosen])
    return spots[0] if count == 1 else spots


def stack_spot(support_points: np.ndarray, obstacle_points: Sequence[np.ndarray], extent: Sequence[float],
               *, overhang_m: float = 0.01) -> np.ndarray | None:
    """Where on a flat top an object stands whole: its middle over the top's middle, where the top is
    as wide as the object each way (less ``overhang_m`` a side) and nothing else stands on it.

    A table with no free place left may still hold the object on top of another it was put down on
    first: the smaller box of a nest on the larger one lifted off it (RoboEXP's idle space, on
    another surface).

    Args:
        support_points: (N, 3) the supporting thing's points; its top is those within 1 cm of the
            highest, at their mean height.
        obstacle_points: every other thing's points: none may stand on the top.
        extent: the object's box (dx, dy, dz).
        overhang_m: how far (m) the object may reach past the top's seen edge on each side.

    Returns:
        (x, y, top z) of the spot, or None where the top is too small, too few points or taken.
    """
    points = np.asarray(support_points, dtype=float).reshape(-1, 3)
    if len(points) < 10:
        return None
    band = points[points[:, 2] >= points[:, 2].max() - 0.01]
    top = float(band[:, 2].mean())  # as a thing's top grasp point has it: where the object will rest
    flat = band[:, :2]
    lo, hi = flat.min(axis=0), flat.max(axis=0)
    if np.any(np.asarray(extent, dtype=float)[:2] > hi - lo + 2 * overhang_m):
        return None
    for other in obstacle_points:
        other = np.asarray(other, dtype=float).reshape(-1, 3)
        on_it = np.all((other[:, :2] >= lo) & (other[:, :2] <= hi), axis=1) & (other[:, 2] > top + 0.005)
        if np.any(on_it):
            return None
    middle = (lo + hi) / 2
    return np.array([middle[0], middle[1], top])


def reach_along(points_xy: np.ndarray, line_y: float, reach_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Where along a table's edge the base may stand to reach points: a pick and its put-down are
    made from one stand, one where both intervals meet.

    Args:
        points_xy: (N, 2) points (x, y).
        line_y: the line y = ``line_y`` (the edge of a table the base slides along).
        reach_m: how far from the base's axis the arm reaches.

    Returns:
        (lo, hi): for each point, the interval [lo, hi] of x on the line from which it lies within
        ``reach_m`` of the base's axis; lo > hi where there is none.
    """
    points = np.atleast_2d(np.asarray(points_xy, dtype=float))
    across = reach_m ** 2 - (points[:, 1] - line_y) ** 2
    half = np.sqrt(np.clip(across, 0.0, None))
    lo, hi = points[:, 0] - half, points[:, 0] + half
    return np.where(across >= 0, lo, np.inf), np.where(across >= 0, hi, -np.inf)
