"""One RGB-D frame cut into per-instance voxel sets in the world frame: what the memory merges.

The segmentation's instance ids are taken only as "these pixels belong together in this frame";
they are kept as a hint, never used to decide which remembered instance a detection is (a real
detector's ids are not stable across frames, and RoboEXP merges by geometry and label instead).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from agent.mapping.camera import Intrinsics, back_project
from agent.perception.voxels import keys_of


@dataclass(frozen=True, eq=False)
class Detection:
    """One instance as seen in one frame: its label and the voxels its pixels fall in (world frame).

    ``hint`` is the segmentation id the frame gave it (meaningful within that frame only);
    ``hits`` counts the pixels per voxel, ``pixels`` all of them.
    """

    hint: int
    label: str
    colour: str | None
    keys: np.ndarray
    hits: np.ndarray
    pixels: int


@dataclass(frozen=True)
class FrameLabel:
    """The label of one segmentation id: its category and, when known, its colour."""

    category: str
    colour: str | None = None


def frame_labels(labels: Mapping[int, Any] | Iterable[Any]) -> dict[int, FrameLabel]:
    """Segmentation id -> label from ``{id: category}``, ``{id: label}`` or objects with ``id``.

    Accepts the agent's `InstanceLabel`s (``id``, ``category``, ``colour``), the world's label dicts
    (``{"id", "category", "colour", ...}``) or a plain mapping of id to category string.

    Args:
        labels: the frame's labels, in any of those forms.

    Returns:
        The labels by segmentation id.
    """
    if isinstance(labels, Mapping):
        items = list(labels.items())
    else:
        items = [(_field(entry, "id"), entry) for entry in labels]
    out: dict[int, FrameLabel] = {}
    for key, value in items:
        if isinstance(value, str):
            out[int(key)] = FrameLabel(value)
        else:
            colour = _field(value, "colour", None)
            out[int(key)] = FrameLabel(str(_field(value, "category")), None if colour is None else str(colour))
    return out


def _field(entry: Any, name: str, *default: Any) -> Any:
    if isinstance(entry, Mapping):
        if name in entry:
            return entry[name]
    elif hasattr(entry, name):
        return getattr(entry, name)
    if default:
        return default[0]
    raise ValueError(f"labels: an entry has no {name!r} ({entry!r})")


def check_frame(depth: np.ndarray, segmentation: np.ndarray, intrinsics: Intrinsics,
                camera_to_world: np.ndarray) -> None:
    """Raise ValueError naming the field when the frame's parts disagree with each other.

    Args:
        depth: the depth image.
        segmentation: the segmentation image.
        intrinsics: the camera's intrinsics.
        camera_to_world: the camera's world pose.

    Raises:
        ValueError: an image's shape differs from the intrinsics', or the pose is not a rigid 4x4.
    """
    size = (intrinsics.height, intrinsics.width)
    if np.shape(depth) != size:
        raise ValueError(f"depth: shape {np.shape(depth)} but the intrinsics say {size}")
    if np.shape(segmentation) != size:
        raise ValueError(f"segmentation: shape {np.shape(segmentation)} but the intrinsics say {size}")
    pose = np.asarray(camera_to_world, dtype=float)
    if pose.shape != (4, 4) or not np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-4):
        raise ValueError("camera_to_world: must be a 4x4 rigid transform")


def check_labels(segmentation: np.ndarray, labels: Mapping[int, FrameLabel]) -> None:
    """Raise ValueError when a segmentation id in the frame has no label.

    Args:
        segmentation: the segmentation image.
        labels: the labels by segmentation id.

    Raises:
        ValueError: naming the ids with no label.
    """
    present = set(np.unique(segmentation[segmentation >= 0]).tolist())
    missing = sorted(present - set(labels))
    if missing:
        raise ValueError(f"labels: no label for segmentation ids {missing}")


def detect(
    depth: np.ndarray,
    segmentation: np.ndarray,
    labels: Mapping[int, FrameLabel],
    intrinsics: Intrinsics,
    camera_to_world: np.ndarray,
    voxel_m: float,
    min_pixels: int = 1,
    max_depth_m: float | None = None,
) -> list[Detection]:
    """Every labelled instance in the frame with at least ``min_pixels`` depth returns, as voxels.

    Pixels farther than ``max_depth_m`` are dropped: depth noise grows with range, and a far, thin
    sliver of an object is more likely to smear into its neighbours' voxels than to help.

    Args:
        depth: the depth image (m; 0 = no return).
        segmentation: the segmentation image (-1 = none).
        labels: the labels by segmentation id.
        intrinsics: the camera's intrinsics.
        camera_to_world: the camera's world pose.
        voxel_m: the voxel size.
        min_pixels: the fewest returns an instance needs.
        max_depth_m: the farthest return kept (all when None).

    Returns:
        The detections.

    Raises:
        ValueError: the frame's parts disagree, or an id has no label.
    """
    check_frame(depth, segmentation, intrinsics, camera_to_world)
    valid = (depth > 0) & (segmentation >= 0)
    if max_depth_m is not None:
        valid &= depth <= max_depth_m
    check_labels(segmentation, labels)
    points = back_project(depth, intrinsics, camera_to_world, valid)
    ids = segmentation[valid]  # the same row-major order back_project walks the mask in
    order = np.argsort(ids, kind="stable")
    ids, points = ids[order], points[order]
    starts = np.flatnonzero(np.r_[True, ids[1:] != ids[:-1]]) if len(ids) else np.array([], dtype=int)
    found = []
    for start, stop in zip(starts, np.r_[starts[1:], len(ids)]):
        if stop - start < min_pixels:
            continue
        hint = int(ids[start])
        keys, hits = keys_of(points[start:stop], voxel_m)
        label = labels[hint]
        found.append(Detection(hint, label.category, label.colour, keys, hits, int(stop - start)))
    return found
