"""Which remembered voxels a new frame shows are no longer there: the memory's depth test.

A remembered voxel that projects into the image *in front of* what the camera now sees there, by
more than a margin, should have been seen and was not, so it is no longer there (a door swung open,
an object picked away). Voxels behind the observed surface (occluded) or outside the image are
kept. The observed depth is taken as the nearest return in the pixel's 3x3 neighbourhood, so a
voxel on the rim of an object that still stands there is not eaten away by the background just
beside its silhouette. The depth test cannot clear what lies within the margin of the surface
behind it (a cup's base on the table), so once most of an instance's visible voxels fail it, the
thing is taken to have moved and its visible rest goes too, unless its own pixel still shows its
label at its depth.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import minimum_filter

from agent.mapping.camera import Intrinsics
from agent.perception.frames import FrameLabel
from agent.perception.instances import Instance


@dataclass(frozen=True, eq=False)
class DepthView:
    """One frame as the depth test reads it.

    ``nearest``: per pixel, the nearest return of its 3x3 neighbourhood (inf where the view is
    free, -inf where a missing return says nothing). ``label_of``: per pixel, the category its
    segment is labelled with ("" for none). ``depth``: the frame's own depth (0 = no return).
    """

    nearest: np.ndarray
    label_of: np.ndarray
    depth: np.ndarray
    intrinsics: Intrinsics
    world_to_camera: np.ndarray


def depth_view(depth: np.ndarray, segmentation: np.ndarray, labels: Mapping[int, FrameLabel],
               intrinsics: Intrinsics, camera_to_world: np.ndarray, no_return_is_free: bool) -> DepthView:
    """Prepare a checked frame once for the depth test of every instance.

    Args:
        depth: (H, W) linear metres, 0 = no return.
        segmentation: (H, W) per-frame segment ids, -1 = nothing.
        labels: segment id -> its label.
        intrinsics: the camera's intrinsics.
        camera_to_world: 4x4, OpenCV camera axes.
        no_return_is_free: whether a pixel without a return sees through to infinity.

    Returns:
        The frame as `stale_voxels` reads it.
    """
    observed = np.where(depth > 0, depth, np.inf)
    nearest = minimum_filter(observed, size=3, mode="nearest")
    if not no_return_is_free:
        nearest = np.where(depth > 0, nearest, -np.inf)  # no return: no evidence either way
    label_of = np.full(segmentation.shape, "", dtype=object)
    for seg_id, label in labels.items():
        label_of[segmentation == seg_id] = label.category
    return DepthView(nearest, label_of, depth, intrinsics, np.linalg.inv(camera_to_world))


def stale_voxels(view: DepthView, inst: Instance, margin_m: float, majority: float) -> np.ndarray:
    """The voxels of ``inst`` the frame looks through, which the memory should forget.

    Its voxels in the image are *visible* unless they lie behind the observed surface (occluded),
    and *stale* if they lie in front of it. When most of the visible voxels are stale, the thing
    has moved, and the visible rest goes too unless its own pixel shows the instance's label at
    its depth: the rest are the voxels within the margin of whatever the thing stood on or against
    (a cup's base on the table, a door's rim against the carcass), which the depth test alone
    cannot clear. The check is strict (the voxel's own pixel, no neighbourhood) because it runs
    only for instances already judged moved, where forgetting a rim voxel too many costs nothing.

    Args:
        view: the frame (`depth_view`).
        inst: a live instance.
        margin_m: how far in front of the observed surface a voxel must lie to be stale
            (`MemoryConfig.stale_margin_m`).
        majority: the share of visible voxels that must be stale before the unconfirmed rest
            goes too (`MemoryConfig.stale_majority`).

    Returns:
        A boolean mask over the instance's voxels; all False when none lies in the image.
    """
    intrinsics = view.intrinsics
    cam = inst.points() @ view.world_to_camera[:3, :3].T + view.world_to_camera[:3, 3]
    z = cam[:, 2]
    ahead = z > 1e-6
    u = np.full(len(z), -1.0)
    v = np.full(len(z), -1.0)
    u[ahead] = intrinsics.fx * cam[ahead, 0] / z[ahead] + intrinsics.cx
    v[ahead] = intrinsics.fy * cam[ahead, 1] / z[ahead] + intrinsics.cy
    inside = ahead & (u >= 0) & (u < intrinsics.width) & (v >= 0) & (v < intrinsics.height)
    stale = np.zeros(len(z), dtype=bool)
    if not inside.any():
        return stale
    cols, rows = u[inside].astype(int), v[inside].astype(int)
    surface = view.nearest[rows, cols]
    stale[inside] = z[inside] < surface - margin_m
    visible = np.zeros(len(z), dtype=bool)
    visible[inside] = np.isfinite(surface) & (z[inside] <= surface + margin_m)
    if visible.sum() and stale.sum() >= majority * visible.sum():
        confirmed = np.zeros(len(z), dtype=bool)
        confirmed[inside] = (view.label_of[rows, cols] == inst.label) & (
            np.abs(z[inside] - view.depth[rows, cols]) <= margin_m)
        stale |= visible & ~confirmed
    return stale
