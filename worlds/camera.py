"""Rendering one RGB-D frame with instance segmentation from the robot's head or wrist camera.

PyBullet's depth buffer is non-linear; it is turned into metres along the optical axis with
z = far·near / (far − (far − near)·d), and pixels at the far plane (nothing hit) become 0, meaning
"no return". The segmentation comes back per body and link and is translated into the scene's
instance ids (a storage piece's doors, drawers and handles have ids of their own), so the frame
speaks the same language as the labels that travel with it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import pybullet as p

from worlds.robot import CameraConfig, camera_pose
from worlds.things import Label

#: (body, link) -> label, link -1 labelling every link of the body without a label of its own.
SegLabels = dict[tuple[int, int], Label]

#: Depth-buffer values this close to 1 are the far plane: no surface there.
_FAR_PLANE = 1.0 - 1e-6


@dataclass(frozen=True)
class Frame:
    """One frame: RGB (H, W, 3) uint8, depth (H, W) float32 metres, seg (H, W) int32 instance ids."""

    rgb: np.ndarray
    depth: np.ndarray
    seg: np.ndarray
    labels: list[Label]
    camera_pose: np.ndarray
    render_ms: float


def linear_depth(buffer: np.ndarray, near: float, far: float) -> np.ndarray:
    """Metric z-depth from an OpenGL depth buffer; 0 where the buffer is at the far plane.

    Args:
        buffer: the depth buffer (0 to 1).
        near: the near plane (m).
        far: the far plane (m).

    Returns:
        The depth (m, float32).
    """
    d = np.asarray(buffer, dtype=np.float64)
    z = far * near / (far - (far - near) * d)
    return np.where(d >= _FAR_PLANE, 0.0, z).astype(np.float32)


def _matrices(camera: CameraConfig, pose: np.ndarray) -> tuple[list[float], list[float]]:
    eye = pose[:3, 3]
    view = p.computeViewMatrix(eye.tolist(), (eye + pose[:3, 2]).tolist(), (-pose[:3, 1]).tolist())
    aspect = camera.width / camera.height
    projection = list(p.computeProjectionMatrixFOV(camera.vfov_deg, aspect, camera.near, camera.far))
    # The tiny renderer samples each pixel at its corner (column c at u = c, row r at v = r + 1).
    # Shifting the image half a pixel makes it sample pixel centres, so (cx, cy) = (W/2, H/2) holds.
    projection[8] += 1.0 / camera.width
    projection[9] += 1.0 / camera.height
    return view, projection


def render(
    client: int,
    camera: CameraConfig,
    base_pose: tuple[float, float, float],
    labels: SegLabels,
) -> Frame:
    """Render what the head camera sees from ``base_pose``; labels only for instances in the frame.

    Args:
        client: the PyBullet client.
        camera: the head camera.
        base_pose: the base's pose (x, y, yaw).
        labels: the labels by body and link.

    Returns:
        The frame.
    """
    return render_at(client, camera, camera_pose(base_pose, camera), labels)


def render_at(client: int, camera: CameraConfig, pose: np.ndarray, labels: SegLabels) -> Frame:
    """Render what a camera with ``camera``'s intrinsics sees from ``pose`` (4x4 camera-to-world,
    OpenCV axes): the head camera, or the wrist camera wherever the arm has put it.

    Args:
        client: the PyBullet client.
        camera: the camera's settings.
        pose: the camera's world pose.
        labels: the labels by body and link.

    Returns:
        The frame.
    """
    view, projection = _matrices(camera, pose)
    started = time.perf_counter()
    _, _, rgba, depth_buffer, body_seg = p.getCameraImage(
        camera.width,
        camera.height,
        view,
        projection,
        renderer=p.ER_TINY_RENDERER,
        flags=p.ER_SEGMENTATION_MASK_OBJECT_AND_LINKINDEX,
        physicsClientId=client,
    )
    render_ms = (time.perf_counter() - started) * 1000.0
    shape = (camera.height, camera.width)
    rgb = np.asarray(rgba, dtype=np.uint8).reshape(*shape, 4)[..., :3].copy()
    depth = linear_depth(np.asarray(depth_buffer).reshape(shape), camera.near, camera.far)
    seg = _instances(np.asarray(body_seg, dtype=np.int64).reshape(shape), labels)
    present = {int(i) for i in np.unique(seg) if i >= 0}
    seen = {label["id"]: label for label in labels.values() if label["id"] in present}
    return Frame(rgb, depth, seg, [seen[i] for i in sorted(seen)], pose, render_ms)


def _instances(raw: np.ndarray, labels: SegLabels) -> np.ndarray:
    """Packed body + (link + 1) << 24 values (-1: background) to instance ids (-1: nothing, or unlabelled)."""
    hit = raw >= 0
    body = np.where(hit, raw & ((1 << 24) - 1), 0)
    link = np.where(hit, (raw >> 24), 0)  # link index + 1: 0 is the base
    bodies = max(int(body.max(initial=0)), max((b for b, _ in labels), default=0)) + 1
    links = max(int(link.max(initial=0)), max((k + 1 for _, k in labels), default=0)) + 1
    table = np.full((bodies, links), -1, dtype=np.int32)
    for (b, k), label in sorted(labels.items(), key=lambda item: item[0][1]):  # whole bodies first
        if k < 0:
            table[b, :] = label["id"]
        else:
            table[b, k + 1] = label["id"]
    return np.where(hit, table[body, link], -1).astype(np.int32)
