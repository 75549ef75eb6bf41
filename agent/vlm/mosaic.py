"""Several views in one image, so that a VLM is asked about all of them at once.

A cabinet with two doors has two compartments, and the robot opens one door at a time (it holds
each door while it looks). No single frame shows the whole inside: shown the view behind the first
door, a VLM sees the cabinet standing open and empty and answers "No" with confidence, although
the hammer lies behind the second. Shown every compartment side by side, it answers about the whole
piece, as a person would after opening every door.

The mosaic is for the VLM only. Its pixels, depth and segmentation are the views' side by side
(shorter views padded below: black, no depth return, no instance); each instance keeps the label
of the view that shows the most of it, and a door or drawer seen standing open in any view is
labelled open (every compartment opened in turn shows as opened). Its intrinsics say only its size, and its pose is the first
view's: nothing may be back-projected from it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from agent.mapping.camera import Intrinsics
from agent.observation import InstanceLabel, Observation


def _pad_rows(array: np.ndarray, height: int, fill: float) -> np.ndarray:
    missing = height - array.shape[0]
    if missing == 0:
        return array
    pad = np.full((missing, *array.shape[1:]), fill, dtype=array.dtype)
    return np.concatenate([array, pad], axis=0)


def side_by_side(views: Sequence[Observation]) -> Observation:
    """One observation showing ``views`` left to right; a single view is returned as it is.

    Args:
        views: the views.

    Returns:
        The observation.

    Raises:
        ValueError: no view.
    """
    if not views:
        raise ValueError("views: at least one view is needed")
    if len(views) == 1:
        return views[0]
    height = max(view.rgb.shape[0] for view in views)
    rgb = np.concatenate([_pad_rows(v.rgb, height, 0) for v in views], axis=1)
    depth = np.concatenate([_pad_rows(v.depth, height, 0.0) for v in views], axis=1)
    segmentation = np.concatenate([_pad_rows(v.segmentation, height, -1) for v in views], axis=1)
    best: dict[int, tuple[int, InstanceLabel]] = {}
    for view in views:
        ids, counts = np.unique(view.segmentation[view.segmentation >= 0], return_counts=True)
        pixels = dict(zip(ids.tolist(), counts.tolist()))
        for label in view.labels:
            count = pixels.get(label.id, 0)
            if label.id not in best or count > best[label.id][0]:
                best[label.id] = (count, label)
    seen_open = {label.id for view in views for label in view.labels if label.state == "open"}
    for instance, (count, label) in best.items():
        if instance in seen_open and label.state != "open":
            best[instance] = (count, replace(label, state="open"))
    first = views[0]
    intrinsics = Intrinsics(rgb.shape[1], height, first.intrinsics.fx, first.intrinsics.fy,
                            first.intrinsics.cx, first.intrinsics.cy)
    labels = tuple(label for _, label in best.values())
    return Observation(rgb, depth, segmentation, labels, intrinsics, first.camera_to_world, views[-1].base_pose)
