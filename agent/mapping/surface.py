"""Which TSDF voxels hold a surface: the zero crossings of the field, one voxel thick.

A band test (|tsdf| below a threshold) is either too thick or too thin. Near the camera a
wall's band is two or three voxels deep, so walls come out fatter than they are and a 0.8 m
doorway narrower than the robot; far away the floor is seen at a grazing angle, where the
projective distance of the voxel nearest the floor grows with range and leaves the band, so far
floor goes missing. The surface itself is where the field changes sign between two neighbouring
voxels; of each such pair the voxel nearer the crossing holds it. That is one voxel thick at
every range and angle.
"""

from __future__ import annotations

import numpy as np


def surface_mask(field: np.ndarray, max_pair_tsdf: float, near_tsdf: float) -> np.ndarray:
    """A boolean mask over a dense block of voxels: true where a surface passes through the voxel.

    A voxel is on a surface when the TSDF changes sign between it and a neighbour along x, y or z
    and it is the nearer of the two to the crossing (the smaller |tsdf|), or when its own value
    says the surface is within ``near_tsdf`` of it. Across a real surface the two values are both
    small: they differ by a voxel's share of the truncation distance, more at a grazing angle
    (about 0.8 for floor 5 m away). A pair whose |tsdf| add up to more than ``max_pair_tsdf`` is
    no surface but a shadow's edge: free space seen past a door jamb (+1, truncated) beside the
    space just behind the jamb (small and negative), which would otherwise narrow every doorway
    seen at an angle.

    A voxel's answer depends on it and its six neighbours only, so a mask computed over part of
    the map is right everywhere but on that part's outer layer.

    Args:
        field: normalised TSDF values (X, Y, Z), NaN where no depth ray has reached.
        max_pair_tsdf: the largest |tsdf| the two voxels of a crossing may add up to.
        near_tsdf: a voxel with |tsdf| up to this is on a surface whatever its neighbours (half a
            voxel over the truncation distance: the surface passes through the voxel's cell).

    Returns:
        The mask, shaped as ``field``.
    """
    magnitude = np.abs(field)
    on_surface = magnitude <= near_tsdf
    for axis in range(3):
        here = [slice(None)] * 3
        there = [slice(None)] * 3
        here[axis], there[axis] = slice(None, -1), slice(1, None)
        a, b = field[tuple(here)], field[tuple(there)]
        size_a, size_b = magnitude[tuple(here)], magnitude[tuple(there)]
        # NaN compares false: an unobserved voxel never crosses.
        crossing = (a * b <= 0) & ~((a == 0) & (b == 0)) & (size_a + size_b <= max_pair_tsdf)
        a_nearer = size_a <= size_b
        on_surface[tuple(here)] |= crossing & a_nearer
        on_surface[tuple(there)] |= crossing & ~a_nearer
    return on_surface
