"""Prompt points: places on the floor in the current image that the VLM is asked to rank (§IV-C).

The paper projects the free space seen in the image onto the map, keeps the free points and
farthest-point samples three of them, which it draws on the image as letters A, B, C. Here a
candidate is a free map cell

- between ``min_distance_m`` and ``max_distance_m`` from the robot (nearer ones are where the robot
  already is; farther ones are too small in the image to point at),
- whose floor point projects inside the image, and
- is in line of sight: the depth image at that pixel is the floor's depth there. A free cell
  behind a wall (seen from another pose) projects inside the image too, but a letter drawn there
  would label the wall, so it is dropped.

Farthest-point sampling starts from a candidate drawn with the caller's rng (as the reference
does, whose start is a random subsample's first point), so successive frames do not always anchor
on the same extreme point, and one seed always gives the same points. Each later point is the
candidate farthest from those already chosen; sampling stops early once that distance falls below
``merge_distance_m``, which is the paper's merging of points closer than 1 m. Fewer than
``min_points`` left means the view offers no choice of direction, and no prompt is made.
"""

from __future__ import annotations

import string
from dataclasses import dataclass

import numpy as np

from agent.mapping.camera import Intrinsics
from agent.mapping.occupancy import ExplorationMap
from agent.planning.window import Window


@dataclass(frozen=True)
class PromptPointConfig:
    """Which free cells may carry a letter, and how many letters (paper: 2–10 m, 3 points, 1 m apart)."""

    min_distance_m: float = 2.0
    max_distance_m: float = 10.0
    max_points: int = 3
    min_points: int = 2
    merge_distance_m: float = 1.0
    floor_z: float = 0.0
    # line of sight: the depth image at the point's pixel is the floor's depth there, within
    # depth_tolerance_m + depth_tolerance_frac · depth (sensor noise grows with range)
    depth_tolerance_m: float = 0.1
    depth_tolerance_frac: float = 0.02


@dataclass(frozen=True)
class PromptPoint:
    """One labelled point: its letter, its world floor position and its pixel (u = column, v = row)."""

    letter: str
    xy: tuple[float, float]
    pixel: tuple[int, int]


def visible_free_cells(world_map: ExplorationMap, robot_xy: tuple[float, float], depth: np.ndarray,
                       intrinsics: Intrinsics, camera_to_world: np.ndarray,
                       config: PromptPointConfig = PromptPointConfig()) -> tuple[np.ndarray, np.ndarray]:
    """Candidate prompt points: world x, y (N, 2) and integer pixels (N, 2) as (u, v).

    Args:
        world_map: the robot's map.
        robot_xy: where the robot stands.
        depth: the frame's depth image (the point must be nearer than what the pixel saw).
        intrinsics: the camera's intrinsics.
        camera_to_world: the camera's world pose.
        config: the distances and floor height of prompt points.

    Returns:
        The points and their pixels.
    """
    spec = world_map.spec
    window = Window.whole(spec.shape)  # narrowed to the box round the robot outside which all is out of range
    robot_cell = tuple(int(v) for v in spec.to_cell(np.asarray(robot_xy, dtype=float)))
    if window.contains(robot_cell):
        window = Window.cell(robot_cell, spec.shape).widened(int(np.ceil(config.max_distance_m / spec.resolution)) + 1)
    xy = spec.to_world(np.argwhere(window.crop(world_map.free)) + np.asarray(window.corner))
    distance = np.hypot(xy[:, 0] - robot_xy[0], xy[:, 1] - robot_xy[1])
    xy = xy[(distance >= config.min_distance_m) & (distance <= config.max_distance_m)]
    floor = np.column_stack([xy, np.full(len(xy), config.floor_z), np.ones(len(xy))])
    in_camera = floor @ np.linalg.inv(camera_to_world).T
    z = in_camera[:, 2]
    ahead = z > 1e-6
    safe_z = np.where(ahead, z, 1.0)
    u = intrinsics.fx * in_camera[:, 0] / safe_z + intrinsics.cx
    v = intrinsics.fy * in_camera[:, 1] / safe_z + intrinsics.cy
    height, width = depth.shape
    inside = ahead & (u >= 0) & (u < width) & (v >= 0) & (v < height)
    pixels = np.column_stack([np.floor(u[inside]), np.floor(v[inside])]).astype(int)
    xy = xy[inside]
    expected = _floor_depth(pixels, intrinsics, camera_to_world, config.floor_z)
    seen = depth[pixels[:, 1], pixels[:, 0]]
    tolerance = config.depth_tolerance_m + config.depth_tolerance_frac * expected
    in_sight = (seen > 0) & (np.abs(seen - expected) <= tolerance)
    return xy[in_sight], pixels[in_sight]


def _floor_depth(pixels: np.ndarray, intrinsics: Intrinsics, camera_to_world: np.ndarray,
                 floor_z: float) -> np.ndarray:
    """Depth at which each pixel's centre ray meets the floor plane (inf where it never does).

    Compared with the depth image instead of the cell's own depth, because at grazing angles one
    pixel spans decimetres of floor: the cell's depth would differ from what its pixel shows by
    that much even in plain sight, and a tolerance that wide would let floor hidden just behind a
    low obstacle through.
    """
    rays = np.column_stack([(pixels[:, 0] + 0.5 - intrinsics.cx) / intrinsics.fx,
                            (pixels[:, 1] + 0.5 - intrinsics.cy) / intrinsics.fy,
                            np.ones(len(pixels))]) @ camera_to_world[:3, :3].T
    drop = floor_z - camera_to_world[2, 3]
    downward = rays[:, 2] * drop > 0
    return np.where(downward, drop / np.where(downward, rays[:, 2], 1.0), np.inf)


def farthest_point_sample(points_xy: np.ndarray, count: int, min_separation_m: float,
                          rng: np.random.Generator) -> np.ndarray:
    """Indices of up to ``count`` points, each the farthest from those before, all ≥ the separation apart.

    The first index is drawn uniformly with ``rng``; none is returned for no points.

    Args:
        points_xy: the points (N, 2).
        count: the most indices returned.
        min_separation_m: the least distance between two chosen points.
        rng: the first index's generator.

    Returns:
        The indices.
    """
    if len(points_xy) == 0 or count <= 0:
        return np.zeros(0, dtype=int)
    chosen = [int(rng.integers(len(points_xy)))]
    nearest = np.hypot(*(points_xy - points_xy[chosen[0]]).T)
    while len(chosen) < count:
        candidate = int(np.argmax(nearest))
        if nearest[candidate] < min_separation_m:
            break
        chosen.append(candidate)
        nearest = np.minimum(nearest, np.hypot(*(points_xy - points_xy[candidate]).T))
    return np.asarray(chosen, dtype=int)


def prompt_points(world_map: ExplorationMap, robot_xy: tuple[float, float], depth: np.ndarray,
                  intrinsics: Intrinsics, camera_to_world: np.ndarray, rng: np.random.Generator,
                  config: PromptPointConfig = PromptPointConfig()) -> list[PromptPoint]:
    """The points to letter on this frame, A first; empty when fewer than ``min_points`` remain.

    Args:
        world_map: the robot's map.
        robot_xy: where the robot stands.
        depth: the frame's depth image.
        intrinsics: the camera's intrinsics.
        camera_to_world: the camera's world pose.
        rng: the sampling's generator.
        config: how many points, how far apart and how far away.

    Returns:
        The prompt points, lettered.
    """
    xy, pixels = visible_free_cells(world_map, robot_xy, depth, intrinsics, camera_to_world, config)
    chosen = farthest_point_sample(xy, config.max_points, config.merge_distance_m, rng)
    if len(chosen) < config.min_points:
        return []
    return [
        PromptPoint(letter, (float(xy[i, 0]), float(xy[i, 1])), (int(pixels[i, 0]), int(pixels[i, 1])))
        for letter, i in zip(string.ascii_uppercase, chosen)
    ]
