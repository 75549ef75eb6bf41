"""Directions read off point sets: principal axes, surface normals, and the handle's snap.

The measuring steps under `agent.perception.part_geometry`: a handle's bar is the first principal
axis of its points, a front's opening direction the most common surface normal near the handle.
Every point and direction is in the world frame (z up). Points that do not determine what is asked
(too few, not finite, degenerate) raise `GeometryError`, which names the input.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

UP = np.array([0.0, 0.0, 1.0])
#: |axis·z| above this is a vertical handle (the paper's threshold).
VERTICAL_COS = 0.7


class GeometryError(ValueError):
    """Points that do not determine the geometry asked for; the text names the input."""


def checked_points(points: np.ndarray, name: str, minimum: int) -> np.ndarray:
    """The input as float points, refused early so that a bad one names itself.

    Args:
        points: (N, 3) points.
        name: what the caller calls them, for the error text.
        minimum: the fewest points the caller's measurement needs.

    Returns:
        The points as an (N, 3) float array.

    Raises:
        GeometryError: wrong shape, fewer than ``minimum`` points, or a non-finite value.
    """
    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise GeometryError(f"{name}: shape {pts.shape}, expected (N, 3)")
    if len(pts) < minimum:
        raise GeometryError(f"{name}: {len(pts)} points, need at least {minimum}")
    if not np.all(np.isfinite(pts)):
        raise GeometryError(f"{name}: not all finite")
    return pts


def unit_vector(vector: np.ndarray, name: str) -> np.ndarray:
    """``vector`` scaled to length 1, so that directions compose without drifting in length.

    Args:
        vector: a direction of any length.
        name: what the caller calls it, for the error text.

    Returns:
        The unit vector along ``vector``.

    Raises:
        GeometryError: ``vector`` has (almost) zero length, so it has no direction.
    """
    v = np.asarray(vector, dtype=float)
    norm = float(np.linalg.norm(v))
    if not norm > 1e-9:
        raise GeometryError(f"{name}: zero-length direction")
    return v / norm


def signed_axis(vector: np.ndarray) -> np.ndarray:
    """One sign for a sign-free axis, so the same line always reads as the same direction.

    Args:
        vector: a direction whose sign carries no meaning (a PCA axis).

    Returns:
        ``vector`` or its negation, whichever has its largest-magnitude component positive.
    """
    return vector if vector[int(np.argmax(np.abs(vector)))] >= 0 else -vector


def principal_axis(points: np.ndarray) -> np.ndarray:
    """The direction along which points spread most: a handle bar's direction.

    Args:
        points: (N, 3) points, at least 2.

    Returns:
        The first PCA axis, unit, signed by `signed_axis`.
    """
    pts = checked_points(points, "points", minimum=2)
    _, _, vt = np.linalg.svd(pts - pts.mean(axis=0), full_matrices=False)
    return signed_axis(vt[0])


def snap_handle_axis(axis: np.ndarray, vertical_cos: float = VERTICAL_COS) -> np.ndarray:
    """The paper's snap of a handle's measured axis: bars are mounted vertical or horizontal.

    Args:
        axis: the measured direction of the bar.
        vertical_cos: |axis·z| above this counts as vertical.

    Returns:
        +z for a vertical bar, else the axis flattened to horizontal (unit, signed).
    """
    axis = unit_vector(axis, "axis")
    if abs(axis[2]) > vertical_cos:
        return UP.copy()
    return signed_axis(unit_vector(np.array([axis[0], axis[1], 0.0]), "axis (flattened)"))


def plane_normal(points: np.ndarray, toward: np.ndarray) -> np.ndarray:
    """The normal of the plane that fits points best, facing the viewer.

    Args:
        points: (N, 3) points, at least 3.
        toward: a point on the side the normal should face (e.g. the camera).

    Returns:
        The smallest PCA axis of the points, turned towards ``toward``.
    """
    pts = checked_points(points, "points", minimum=3)
    centre = pts.mean(axis=0)
    _, _, vt = np.linalg.svd(pts - centre, full_matrices=False)
    normal = vt[2]
    return normal if normal @ (np.asarray(toward, float) - centre) >= 0 else -normal


def surface_normals(points: np.ndarray, toward: np.ndarray, k: int = 16) -> np.ndarray:
    """Per-point surface normals, from each point's neighbourhood.

    Args:
        points: (N, 3) points, at least 3.
        toward: a point on the side every normal should face (e.g. the camera).
        k: how many nearest points make a neighbourhood.

    Returns:
        (N, 3) normals: the smallest PCA axis of each point's ``k`` nearest, facing ``toward``.
    """
    pts = checked_points(points, "points", minimum=3)
    k = min(k, len(pts))
    _, neighbours = cKDTree(pts).query(pts, k=k)
    local = pts[neighbours] - pts[neighbours].mean(axis=1, keepdims=True)
    _, vectors = np.linalg.eigh(np.einsum("nki,nkj->nij", local, local))
    normals = vectors[:, :, 0]  # eigh sorts eigenvalues ascending
    flip = np.einsum("ni,ni->n", normals, np.asarray(toward, float) - pts) < 0
    normals[flip] *= -1
    return normals


#: Surfaces whose normal's vertical part is below this count as upright (45°).
UPRIGHT_SIN = math.sin(math.radians(45.0))


def front_normal(points: np.ndarray, toward: np.ndarray, level: bool = True,
                 tolerance_deg: float = 15.0, k: int = 16) -> np.ndarray:
    """The most common surface normal of a front: the paper's opening direction.

    The mode, not the mean, because the points of a front near a handle include its edges and the
    carcass beside it, whose normals point sideways. With ``level``, of the upright surfaces only
    (normals within 45° of the horizontal), where there are any: a drawer looked into is
    remembered with its floor, whose normals outnumbered the front's; levelled, the floor's made a
    front turned 40° off, and the box a closed drawer fills behind its front was laid out before
    the chest, over the spot a box was to be put down (recursive 1120 of tuning-wide).

    Args:
        points: (N, 3) points of the front, at least 3.
        toward: a point on the side the normal should face (the camera).
        level: drop the vertical component: storage stands upright, so a front's normal is
            horizontal and any tilt is noise.
        tolerance_deg: normals within this angle of each other count as the same.
        k: neighbourhood size of `surface_normals`.

    Returns:
        The unit normal most points agree on, facing ``toward``.
    """
    pts = checked_points(points, "points", minimum=3)
    normals = surface_normals(pts, toward, k) if len(pts) > k else plane_normal(pts, toward)[None, :]
    if level and np.any(upright := np.abs(normals[:, 2]) < UPRIGHT_SIN):
        normals = normals[upright]
    cos = math.cos(math.radians(tolerance_deg))
    candidates = normals[np.linspace(0, len(normals) - 1, min(len(normals), 400)).astype(int)]
    support = (candidates @ normals.T > cos).sum(axis=1)
    best = candidates[int(np.argmax(support))]
    normal = unit_vector(normals[normals @ best > cos].mean(axis=0), "normals")
    if level:
        normal = unit_vector(np.array([normal[0], normal[1], 0.0]), "normal (levelled): the front is horizontal")
    return normal
