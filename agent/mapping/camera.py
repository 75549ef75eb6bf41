"""Pinhole camera geometry shared by mapping, prompting and acting: intrinsics, back-projection,
where a picture begins."""

from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np


@dataclass(frozen=True)
class Intrinsics:
    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def from_meta(cls, camera: dict) -> Intrinsics:
        """Intrinsics read from an observation's ``camera`` metadata.

        Args:
            camera: the metadata's ``width``, ``height``, ``fx``, ``fy``, ``cx``, ``cy``.

        Returns:
            The intrinsics.
        """
        return cls(int(camera["width"]), int(camera["height"]), float(camera["fx"]), float(camera["fy"]),
                   float(camera["cx"]), float(camera["cy"]))

    def matrix(self) -> np.ndarray:
        """The 3x3 pinhole matrix K.

        Returns:
            K.
        """
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])


def back_project(
    depth: np.ndarray,
    intrinsics: Intrinsics,
    camera_to_world: np.ndarray,
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """World points (N, 3) of the pixels with a depth return (depth > 0), optionally within ``mask``.

    Depth is linear z along the optical axis; the camera frame is OpenCV's (x right, y down, z ahead).

    Args:
        depth: the depth image (m; 0 = no return).
        intrinsics: the camera's intrinsics.
        camera_to_world: the camera's world pose (4x4).
        mask: the pixels to keep (all with a return when None).

    Returns:
        The points.
    """
    valid = depth > 0
    if mask is not None:
        valid &= mask
    height, width = depth.shape
    z = depth[valid].astype(float)
    points = np.empty((len(z), 4))
    points[:, 0] = np.broadcast_to(np.arange(width) + 0.5 - intrinsics.cx, (height, width))[valid] * z / intrinsics.fx
    points[:, 1] = np.broadcast_to((np.arange(height) + 0.5 - intrinsics.cy)[:, None], (height, width))[valid] * z / intrinsics.fy
    points[:, 2] = z
    points[:, 3] = 1.0
    return (points @ camera_to_world.T)[:, :3]


def narrow_view_mask(height: int, width: int) -> np.ndarray:
    """The paper's "narrow view": the middle half of the columns and the lower half of the rows.

    Only what the camera sees there counts as explored, because a VLM reasons well only about what
    is near and central in the image (Explore until Confident, §IV-B).

    Args:
        height: the image's rows.
        width: the image's columns.

    Returns:
        The mask (height, width).
    """
    mask = np.zeros((height, width), dtype=bool)
    mask[height // 2 :, width // 4 : width - width // 4] = True
    return mask


def nearest_seen_ahead(intrinsics: Intrinsics, camera_to_world: np.ndarray, z: float, origin_xy: np.ndarray,
                       ahead: np.ndarray) -> float:
    """How far ahead of ``origin_xy`` (along the unit vector ``ahead``) the camera's lowest central
    ray meets the horizontal plane at height ``z``: nearer than that, nothing at that height is in
    its picture (inf when that ray never comes down to it). A robot's head camera misses the strip
    of table just before it so.

    Args:
        intrinsics: the camera's intrinsics.
        camera_to_world: the camera's world pose (4x4).
        z: the plane's height (m).
        origin_xy: where the distance is measured from.
        ahead: the unit vector along which it is measured.

    Returns:
        The distance (m), or inf.
    """
    k = intrinsics
    ray = camera_to_world[:3, :3] @ np.array([0.0, (k.height - 1 - k.cy) / k.fy, 1.0])
    origin = camera_to_world[:3, 3]
    if ray[2] >= -1e-9 or origin[2] <= z:
        return math.inf
    hit = origin + (z - origin[2]) / ray[2] * ray
    return float((hit[:2] - np.asarray(origin_xy, dtype=float)[:2]) @ np.asarray(ahead, dtype=float)[:2])
