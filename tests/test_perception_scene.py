"""A tiny ray caster for the perception tests: axis-aligned boxes to depth and segmentation.

The perception tests need frames whose every pixel is known exactly, from any camera pose, without
a simulator: each pixel's ray (OpenCV camera axes, pixel centres at c + 0.5, r + 0.5, as
worlds.robot has it) is cut against every box with the slab method. The ray's direction has unit
z in the camera frame, so the hit parameter *is* the linear depth the Observation carries. The tests
here check the caster against back-projection, so the other perception tests can trust it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from agent.mapping.camera import Intrinsics, back_project

INTRINSICS = Intrinsics(200, 150, 160.0, 160.0, 100.0, 75.0)


@dataclass(frozen=True)
class Box:
    """An axis-aligned box with a segmentation id and a label (category)."""

    id: int
    label: str
    lo: tuple[float, float, float]
    hi: tuple[float, float, float]

    @classmethod
    def at(cls, id: int, label: str, center: Sequence[float], size: Sequence[float]) -> Box:
        c, s = np.asarray(center, float), np.asarray(size, float)
        return cls(id, label, tuple(c - s / 2), tuple(c + s / 2))  # type: ignore[arg-type]

    @property
    def center(self) -> np.ndarray:
        return (np.asarray(self.lo) + np.asarray(self.hi)) / 2


def look_at(eye: Sequence[float], target: Sequence[float]) -> np.ndarray:
    """4x4 camera-to-world, OpenCV axes (x right, y down, z ahead), world z up."""
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    ahead = (target - eye) / np.linalg.norm(target - eye)
    right = np.cross(ahead, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = right, np.cross(ahead, right), ahead, eye
    return pose


def render(boxes: Sequence[Box], pose: np.ndarray, intrinsics: Intrinsics = INTRINSICS, noise_m: float = 0.0,
           rng: np.random.Generator | None = None) -> tuple[np.ndarray, np.ndarray, dict[int, str]]:
    """(depth float32 metres, 0 = nothing; segmentation int32, -1 = nothing; labels of ids in view)."""
    rows, cols = np.indices((intrinsics.height, intrinsics.width))
    ray_cam = np.stack([(cols + 0.5 - intrinsics.cx) / intrinsics.fx, (rows + 0.5 - intrinsics.cy) / intrinsics.fy,
                        np.ones(rows.shape)], axis=-1).reshape(-1, 3)
    direction = ray_cam @ pose[:3, :3].T
    origin = pose[:3, 3]
    depth = np.full(len(direction), np.inf)
    seg = np.full(len(direction), -1, dtype=np.int32)
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse = 1.0 / direction
        for box in boxes:
            t1 = (np.asarray(box.lo) - origin) * inverse
            t2 = (np.asarray(box.hi) - origin) * inverse
            t1 = np.where(np.isnan(t1), -np.inf, t1)
            t2 = np.where(np.isnan(t2), np.inf, t2)
            near = np.minimum(t1, t2).max(axis=1)
            far = np.maximum(t1, t2).min(axis=1)
            hit = (far >= near) & (near > 1e-6) & (near < depth)
            depth[hit], seg[hit] = near[hit], box.id
    depth[~np.isfinite(depth)] = 0.0
    if noise_m > 0:
        assert rng is not None, "noise needs a seeded generator"
        depth = np.where(depth > 0, depth + rng.normal(0.0, noise_m, depth.shape), 0.0)
    shape = (intrinsics.height, intrinsics.width)
    present = set(np.unique(seg).tolist()) - {-1}
    labels = {box.id: box.label for box in boxes if box.id in present}
    return depth.reshape(shape).astype(np.float32), seg.reshape(shape), labels


def test_a_wall_straight_ahead_is_at_its_distance_everywhere() -> None:
    pose = look_at((0.0, 0.0, 1.0), (0.0, 1.0, 1.0))
    depth, seg, labels = render([Box(7, "wall", (-5.0, 2.0, -5.0), (5.0, 2.1, 5.0))], pose)
    assert np.allclose(depth, 2.0, atol=1e-5)
    assert np.all(seg == 7) and labels == {7: "wall"}


def test_back_projected_pixels_lie_on_the_box_they_hit() -> None:
    box = Box.at(3, "crate", (0.1, 1.0, 0.6), (0.3, 0.2, 0.25))
    pose = look_at((-0.5, -0.4, 1.3), box.center)
    depth, seg, _ = render([box], pose)
    points = back_project(depth, INTRINSICS, pose, seg == 3)
    assert len(points) > 500
    assert np.all(points >= np.asarray(box.lo) - 1e-4) and np.all(points <= np.asarray(box.hi) + 1e-4)


def test_the_nearer_box_wins_the_pixel() -> None:
    pose = look_at((0.0, 0.0, 1.0), (0.0, 1.0, 1.0))
    front = Box.at(1, "front", (0.0, 1.0, 1.0), (0.2, 0.05, 0.2))
    back = Box.at(2, "back", (0.0, 2.0, 1.0), (4.0, 0.05, 4.0))
    depth, seg, _ = render([back, front], pose)
    centre = (INTRINSICS.height // 2, INTRINSICS.width // 2)
    assert seg[centre] == 1 and abs(depth[centre] - 0.975) < 1e-5
    assert seg[0, 0] == 2


#: Board, front and handle sizes as worlds.storage has them (board 1.8 cm, front 2 cm, bar 1.6 cm).
BOARD, FRONT, BAR, HANDLE_OUT = 0.018, 0.02, 0.016, 0.035


@dataclass(frozen=True)
class Front:
    """A door or drawer front on a `storage` piece: x and z span, hinge side for doors."""

    kind: str
    x: tuple[float, float]
    z: tuple[float, float]
    hinge: str | None = None


def handle_boxes(front: Front, id: int, y_face: float) -> list[Box]:
    """The bar and two posts of ``front``'s handle, as worlds.urdf places them: vertical near a door's
    free edge, horizontal across a drawer's middle, the bar ``HANDLE_OUT`` in front of the face."""
    (x0, x1), (z0, z1) = front.x, front.z
    y = y_face - HANDLE_OUT
    if front.kind == "door":
        length = float(np.clip(0.4 * (z1 - z0), 0.08, 0.3))
        inset = min(0.05, 0.2 * (x1 - x0))
        centre = np.array([x1 - inset if front.hinge == "left" else x0 + inset, y, (z0 + z1) / 2])
        along = np.array([0.0, 0.0, 1.0])
    else:
        length = float(np.clip(0.4 * (x1 - x0), 0.08, 0.3))
        centre = np.array([(x0 + x1) / 2, y, (z0 + z1) / 2])
        along = np.array([1.0, 0.0, 0.0])
    across = np.array([1.0, 1.0, 1.0]) - along
    boxes = [Box.at(id, "handle", centre, along * length + across * BAR)]
    for s in (-1.0, 1.0):
        post = centre + along * s * (length / 2 - BAR)
        lo = post - across * 0.4 * BAR
        hi = post + across * 0.4 * BAR
        lo[1], hi[1] = y + BAR / 2, y_face
        boxes.append(Box(id, "handle", tuple(lo), tuple(hi)))  # type: ignore[arg-type]
    return boxes


def storage(first_id: int, label: str, x: tuple[float, float], y: tuple[float, float], z: tuple[float, float],
            fronts: Sequence[Front]) -> list[Box]:
    """A hollow carcass (five boards, one id) facing -y, its fronts just in front of y[0], their handles.

    Ids: the carcass ``first_id``, front k ``first_id + 1 + 2k``, its handle the next one.
    """
    (x0, x1), (y0, y1), (z0, z1), t = x, y, z, BOARD
    boards = [((x0, y0, z0), (x1, y1, z0 + t)), ((x0, y0, z1 - t), (x1, y1, z1)), ((x0, y0, z0), (x0 + t, y1, z1)),
              ((x1 - t, y0, z0), (x1, y1, z1)), ((x0, y1 - t, z0), (x1, y1, z1))]
    boxes = [Box(first_id, label, lo, hi) for lo, hi in boards]
    for k, front in enumerate(fronts):
        part_id = first_id + 1 + 2 * k
        boxes.append(Box(part_id, front.kind, (front.x[0], y0 - FRONT, front.z[0]), (front.x[1], y0, front.z[1])))
        boxes.extend(handle_boxes(front, part_id + 1, y0 - FRONT))
    return boxes
