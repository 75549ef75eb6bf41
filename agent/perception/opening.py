"""How far a door or drawer stands open, measured from a view of it.

What a skill's own account of the motion cannot tell: a part held back (by the end of its travel,
by the robot's own body in a door's swing) stops there while the hand pulls on. The part's points
as seen closed are carried through candidate openings (`agent.perception.part_motion`) and the
opening that lays them best onto what the camera sees now is taken.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from agent.perception.directions import checked_points
from agent.perception.part_geometry import PartGeometry
from agent.perception.part_motion import part_motion


def fit_opening(geometry: PartGeometry, closed_points: np.ndarray, seen_points: np.ndarray, most: float,
                steps: int = 80) -> tuple[float, float]:
    """The opening in [0, ``most``] that carries the part as seen closed best onto a view of it.

    Args:
        geometry: the part as seen closed.
        closed_points: (N, 3) points of the part as seen closed, at least 3.
        seen_points: (M, 3) points seen now (often only part of it), at least 3.
        most: the largest opening tried (radians for a door, metres for a drawer).
        steps: how many equal steps divide [0, ``most``].

    Returns:
        (opening, the median distance in m from each seen point to the carried ones).
    """
    closed = checked_points(closed_points, "closed_points", 3)
    seen = checked_points(seen_points, "seen_points", 3)
    best = (0.0, math.inf)
    for amount in np.linspace(0.0, float(most), steps + 1):
        motion = part_motion(geometry, float(amount))
        distance, _ = cKDTree(closed @ motion[:3, :3].T + motion[:3, 3]).query(seen)
        score = float(np.median(distance))
        if score < best[1]:
            best = (float(amount), score)
    return best


def opening_seen(geometry: PartGeometry, closed_points: np.ndarray, views: Sequence[np.ndarray], reported: float,
                 near_m: float, fit_m: float) -> float | None:
    """How far the part stands open by the view of it among ``views``.

    The views whose centre lies within ``near_m`` of where ``reported`` would carry the part are
    tried nearest first; the first that `fit_opening` (up to a quarter beyond ``reported``) carries
    the part onto within ``fit_m`` (median) gives the answer. With the part's own view hidden
    (behind the arm, say), the nearest may be its neighbour's, a drawer's height away, which no
    opening fits.

    Args:
        geometry: the part as seen closed.
        closed_points: (N, 3) points of the part as seen closed, at least 3.
        views: point sets of the part's kind seen now.
        reported: the opening the skill reports.
        near_m: how far a view's centre may lie from where the reported opening puts the part.
        fit_m: the largest median misfit accepted.

    Returns:
        The measured opening, or None when no view is of this part.
    """
    closed = checked_points(closed_points, "closed_points", 3)
    motion = part_motion(geometry, reported)
    expected = motion[:3, :3] @ closed.mean(axis=0) + motion[:3, 3]
    near = sorted((float(np.linalg.norm(points.mean(axis=0) - expected)), k) for k, points in enumerate(views)
                  if len(points) >= 3)
    for distance, k in near:
        if distance > near_m:
            break
        amount, misfit = fit_opening(geometry, closed, views[k], 1.25 * reported)
        if misfit <= fit_m:
            return amount
    return None
