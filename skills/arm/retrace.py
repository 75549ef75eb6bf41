"""The way back along moves the arm has made, for a pick that fails while its hand carries the
object: carried back along them, the object is put down where it was grasped, rather than let go
of wherever the arm stopped (a box that met a drawer on its carry was let go of on the drawer's
edge, out of its place for good, and looked for again four times as a new thing: recursive 1037
of tuning-wide).

Pure: plain joint arrays and the plan's `skills.arm.skill_plan.Step`\\ s, no world.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from skills.arm.skill_plan import Step

#: One sample of a move in this many is kept as a waypoint of the way back.
EVERY_SAMPLES = 5


def way_back(moves: Sequence[Step], q: np.ndarray, every: int = EVERY_SAMPLES) -> np.ndarray:
    """Joint waypoints from ``q`` back along ``moves`` to where the first of them began.

    Args:
        moves: the moves run, in order, each with its samples; the arm stopped in the last, at ``q``
            (or before it began).
        q: where the arm is.
        every: one sample in this many is kept (the move's first and last always).

    Returns:
        (k, dof) waypoints: ``q`` first, the first move's first sample last, no two in a row alike.

    Raises:
        ValueError: no moves, or one without samples.
    """
    if not moves or any(move.samples is None or not len(move.samples) for move in moves):
        raise ValueError("way back: moves with samples are needed")
    here = np.asarray(q, dtype=float)
    last = np.asarray(moves[-1].samples, dtype=float)
    stopped = int(np.argmin(np.abs(last - here).max(axis=1)))
    legs = [last[:stopped + 1], *(np.asarray(move.samples, dtype=float) for move in moves[:-1][::-1])]
    points = [here]
    for leg in legs:
        backwards = leg[::-1]
        points.extend([*backwards[::every], backwards[-1]])
    path = np.array(points)
    apart = np.r_[True, np.abs(np.diff(path, axis=0)).max(axis=1) > 1e-9]
    return path[apart]
