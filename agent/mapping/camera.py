"""Pinhole camera geometry shared by mapping and prompting: intrinsics, back-projection."""

from __future__ import annotations

from dataclasses import dataclass

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
        return cls(int(camera["width"]), int(camera["height"]), float(camera["fx"]), float(camera["fy"]),
                   float(camera["cx"]), float(camera["cy"]))

    def matrix(self) -> np.ndarray:
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])


def back_project(
    depth: np.ndarray,
    intrinsics: Intrinsics,
    camera_to_world: np.ndarray,
    mask: np.ndarray | None = None,
) -> np.ndarray:
    """World points (N, 3) of the pixels with a depth return (depth > 0), optionally within ``mask``.

    Depth is linear z along the optical axis; the camera frame is OpenCV's (x right, y down, z ahead).
    """
    valid = depth > 0
    if mask is not None:
        valid &= mask
    rows, cols = np.nonzero(valid)
    z = depth[rows, cols].astype(float)
    x = (cols + 0.5 - intrinsics.cx) * z / intrinsics.fx
    y = (rows + 0.5 - intrinsics.cy) * z / intrinsics.fy
    points = np.stack([x, y, z, np.ones_like(z)], axis=1)
    return (points @ camera_to_world.T)[:, :3]


def narrow_view_mask(height: int, width: int) -> np.ndarray:
    """The paper's "narrow view": the middle half of the columns and the lower half of the rows.

    Only what the camera sees there counts as explored, because a VLM reasons well only about what
    is near and central in the image (Explore until Confident, §IV-B).
    """
    mask = np.zeros((height, width), dtype=bool)
    mask[height // 2 :, width // 4 : width - width // 4] = True
    return mask
