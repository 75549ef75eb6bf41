"""Distances to line segments, for the arm's skeleton and its paths."""

from __future__ import annotations

import numpy as np


def nearest_on_segments(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """The point of a set of segments nearest each of ``points``.

    Args:
        points: (N, 3) points.
        segments: (m ≥ 1, 2, 3) the segments' ends.

    Returns:
        (N, 3) the nearest points of the segments.
    """
    best = np.full(len(points), np.inf)
    nearest = np.zeros_like(points)
    for start, end in segments:
        along = end - start
        share = np.clip((points - start) @ along / max(float(along @ along), 1e-12), 0.0, 1.0)
        foot = start + share[:, None] * along
        gap = np.linalg.norm(points - foot, axis=1)
        closer = gap < best
        best[closer], nearest[closer] = gap[closer], foot[closer]
    return nearest


def distance_to_segment(point: np.ndarray, start: np.ndarray, end: np.ndarray) -> float:
    """How far a point is from a segment.

    Args:
        point: (3,) the point.
        start: (3,) one end of the segment.
        end: (3,) its other end (the same as ``start``: a point).

    Returns:
        The distance (m).
    """
    point = np.asarray(point, dtype=float)
    foot = nearest_on_segments(point[None, :], np.array([[start, end]], dtype=float))[0]
    return float(np.linalg.norm(point - foot))
