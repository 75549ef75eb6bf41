"""What a closed drawer fills behind its front, which no camera sees.

Of a closed drawer the memory holds its front only. Its box runs back from there into the chest,
and an arm working in the open drawer below reaches up into it: a box lifted in a chest's lower
drawer met the bottom of the closed drawer above, which the plan had taken for free space
(recursive 1037, 1039 and 1050 of tuning-wide). The box's bottom and top are laid out here as
points, for the plans to keep off as they keep off what was seen: its front's width and height,
from the front back as far as the chest reaches behind it.
"""

from __future__ import annotations

import numpy as np

from agent.perception.directions import checked_points, front_normal

#: How far apart (m) the points laid on a hidden face are: the memory's voxels, doubled.
FACE_SPACING_M = 0.02


def closed_drawer_faces(front: np.ndarray, carcass: np.ndarray, eye: np.ndarray,
                        spacing_m: float = FACE_SPACING_M) -> np.ndarray:
    """Points on the bottom and the top of the box a closed drawer fills behind its front.

    Args:
        front: (N, 3) points of the drawer's front, at least 3.
        carcass: (M, 3) points of the piece it belongs to (how far back the box can reach).
        eye: where the front was seen from (its normal faces that way).
        spacing_m: how far apart the points are.

    Returns:
        (K, 3) world points, none where the carcass shows no depth behind the front.
    """
    front = checked_points(front, "front", minimum=3)
    carcass = np.asarray(carcass, dtype=float).reshape(-1, 3)
    normal = front_normal(front, np.asarray(eye, dtype=float))
    across = np.cross([0.0, 0.0, 1.0], normal)
    across /= np.linalg.norm(across)
    face = float((front @ normal).max())
    depth = float((face - carcass @ normal).max(initial=0.0))
    if depth < spacing_m:
        return np.zeros((0, 3))
    sideways = front @ across
    along = np.arange(float(sideways.min()), float(sideways.max()) + 1e-9, spacing_m)
    back = np.arange(spacing_m, depth + 1e-9, spacing_m)
    u, t = (grid.ravel() for grid in np.meshgrid(along, back))
    plane = (face - t)[:, None] * normal + u[:, None] * across
    return np.vstack([plane + [0.0, 0.0, height] for height in (float(front[:, 2].min()), float(front[:, 2].max()))])
