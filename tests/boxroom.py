"""An analytic room for mapping tests: axis-aligned boxes and a floor, depth images by ray casting.

The depth a test feeds the map is exact (no renderer, no noise), so what the map makes of it is
the map's own doing: a free cell missing, a doorway closed or a frontier lost is a mapping bug.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from agent.mapping.camera import Intrinsics
from worlds.robot import CameraConfig, camera_pose

Box = tuple[float, float, float, float, float, float]  # xmin, ymin, zmin, xmax, ymax, zmax


@dataclass(frozen=True)
class BoxRoom:
    """A floor (z = 0 over ``floor`` = (xmin, ymin, xmax, ymax)) and solid boxes; nothing else
    returns a ray."""

    floor: tuple[float, float, float, float]
    boxes: list[Box] = field(default_factory=list)

    def depth(self, camera_to_world: np.ndarray, intrinsics: Intrinsics) -> np.ndarray:
        """Linear depth (metres along the optical axis; 0 where a ray hits nothing)."""
        rows, cols = np.mgrid[0:intrinsics.height, 0:intrinsics.width]
        rays_camera = np.stack([(cols + 0.5 - intrinsics.cx) / intrinsics.fx,
                                (rows + 0.5 - intrinsics.cy) / intrinsics.fy,
                                np.ones(rows.shape)], axis=-1).reshape(-1, 3)
        directions = rays_camera @ camera_to_world[:3, :3].T  # z along the optical axis is 1 per unit
        origin = camera_to_world[:3, 3]
        t = np.full(len(directions), np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            down = directions[:, 2] < 0
            t_floor = np.where(down, -origin[2] / directions[:, 2], np.inf)
            hit = origin[None, :2] + t_floor[:, None] * directions[:, :2]
            x0, y0, x1, y1 = self.floor
            on_floor = (hit[:, 0] >= x0) & (hit[:, 0] <= x1) & (hit[:, 1] >= y0) & (hit[:, 1] <= y1)
            t = np.where(down & on_floor, t_floor, t)
            for box in self.boxes:
                low, high = np.array(box[:3]), np.array(box[3:])
                t0 = (low[None, :] - origin[None, :]) / directions
                t1 = (high[None, :] - origin[None, :]) / directions
                near = np.nanmax(np.minimum(t0, t1), axis=1)
                far = np.nanmin(np.maximum(t0, t1), axis=1)
                enters = (near <= far) & (far > 0) & (near > 0)
                t = np.where(enters & (near < t), near, t)
        # The ray direction's camera z is 1, so the ray parameter is the depth along the optical axis.
        return np.where(np.isfinite(t), t, 0.0).reshape(intrinsics.height, intrinsics.width)

    def floor_hits(self, camera_to_world: np.ndarray, intrinsics: Intrinsics, depth: np.ndarray) -> np.ndarray:
        """World (x, y) of the pixels whose ray ended on the floor."""
        from agent.mapping.camera import back_project

        points = back_project(depth, intrinsics, camera_to_world)
        return points[np.abs(points[:, 2]) < 1e-6][:, :2]


def walls_with_doorway(x0: float, y0: float, x1: float, y1: float, door_y: tuple[float, float],
                       thickness: float = 0.1, height: float = 2.5) -> list[Box]:
    """The four walls around the interior (x0, y0)-(x1, y1), outside it, with a doorway in the east
    wall (x = x1) between ``door_y``."""
    t = thickness
    return [
        (x0 - t, y0 - t, 0.0, x1 + t, y0, height),  # south
        (x0 - t, y1, 0.0, x1 + t, y1 + t, height),  # north
        (x0 - t, y0, 0.0, x0, y1, height),  # west
        (x1, y0, 0.0, x1 + t, door_y[0], height),  # east, below the doorway
        (x1, door_y[1], 0.0, x1 + t, y1, height),  # east, above the doorway
    ]


def head_camera() -> tuple[CameraConfig, Intrinsics]:
    camera = CameraConfig()
    return camera, Intrinsics(camera.width, camera.height, *camera.intrinsics())


def survey(room: BoxRoom, world_map, xy: tuple[float, float], headings: int = 8) -> np.ndarray:
    """Turn on the spot at ``xy`` and fuse one frame per heading; returns the floor hits (N, 2)."""
    camera, intrinsics = head_camera()
    hits = []
    for k in range(headings):
        pose = camera_pose((xy[0], xy[1], 2 * np.pi * k / headings), camera)
        depth = room.depth(pose, intrinsics)
        world_map.integrate(depth, intrinsics, pose, xy)
        hits.append(room.floor_hits(pose, intrinsics, depth))
    return np.vstack(hits)
