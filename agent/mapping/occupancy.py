"""The 2D maps the planners use, derived from the TSDF and the camera's narrow view.

- occupied: a column holds a surface voxel between ``obstacle_min_z`` and the robot's height;
- floor seen: a column holds a surface voxel at floor height;
- free: floor seen and not occupied, or near a pose the robot has stood on;
- explored: hit by a narrow-view ray (the middle half of the columns, lower half of the rows), or
  near a pose the robot has stood on.

"Near a pose" is the head camera's blind zone (``near_field_radius``): the floor closer than the
lower edge of the image is never in view, yet the robot has just been there. Counting it as free
and explored lets frontiers form at its edge, so a robot that starts facing a wall turns away.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from agent.mapping.camera import Intrinsics, back_project, narrow_view_mask
from agent.mapping.grid import GridSpec
from agent.mapping.tsdf import TsdfConfig, TsdfMap, Voxels


@dataclass(frozen=True)
class OccupancyConfig:
    """Heights and thresholds of the 2D projection, in metres unless said otherwise."""

    size_m: float = 48.0  # the largest homes are 22.4 m long, and the robot may start at one end
    resolution: float = 0.1
    floor_band: tuple[float, float] = (-0.12, 0.08)
    obstacle_min_z: float = 0.12
    obstacle_max_z: float = 1.6
    surface_tsdf: float = 0.3  # |normalised TSDF| below this is a surface voxel
    robot_radius: float = 0.25
    near_field_radius: float = 1.0  # floor the head camera cannot see around a pose it stood on
    tsdf: TsdfConfig = field(default_factory=TsdfConfig)


def project_columns(spec: GridSpec, voxels: Voxels, config: OccupancyConfig) -> tuple[np.ndarray, np.ndarray]:
    """(floor_seen, occupied) boolean grids from the observed surface voxels."""
    surface = np.abs(voxels.tsdf) < config.surface_tsdf
    points = voxels.points[surface]
    cells = spec.to_cell(points[:, :2])
    inside = spec.inside(cells)
    points, cells = points[inside], cells[inside]
    z = points[:, 2]
    floor_seen = np.zeros(spec.shape, dtype=bool)
    occupied = np.zeros(spec.shape, dtype=bool)
    at_floor = (z >= config.floor_band[0]) & (z <= config.floor_band[1])
    floor_seen[cells[at_floor, 0], cells[at_floor, 1]] = True
    obstacle = (z >= config.obstacle_min_z) & (z <= config.obstacle_max_z)
    occupied[cells[obstacle, 0], cells[obstacle, 1]] = True
    return floor_seen, occupied


class ExplorationMap:
    """The robot's picture of the home so far: TSDF plus the 2D free, occupied and explored grids."""

    def __init__(self, start_xy: tuple[float, float], config: OccupancyConfig = OccupancyConfig()) -> None:
        self.config = config
        self.spec = GridSpec.centred(start_xy, config.size_m, config.resolution)
        self.tsdf = TsdfMap(config.tsdf)
        self.explored = np.zeros(self.spec.shape, dtype=bool)
        self.stood = np.zeros(self.spec.shape, dtype=bool)
        self.floor_seen = np.zeros(self.spec.shape, dtype=bool)
        self.occupied = np.zeros(self.spec.shape, dtype=bool)
        self.bumped = np.zeros(self.spec.shape, dtype=bool)

    def integrate(self, depth: np.ndarray, intrinsics: Intrinsics, camera_to_world: np.ndarray,
                  robot_xy: tuple[float, float]) -> None:
        """Fuse one frame taken with the robot at ``robot_xy``."""
        self.tsdf.integrate(depth, intrinsics, camera_to_world)
        self.floor_seen, occupied = project_columns(self.spec, self.tsdf.voxels(), self.config)
        self.occupied = occupied | self.bumped
        self.stood |= self.spec.disc(robot_xy, self.config.near_field_radius) & ~self.occupied
        narrow = back_project(depth, intrinsics, camera_to_world, narrow_view_mask(*depth.shape))
        cells = self.spec.to_cell(narrow[:, :2])
        cells = cells[self.spec.inside(cells)]
        self.explored[cells[:, 0], cells[:, 1]] = True
        self.explored |= self.stood

    def mark_contact(self, point_xy: tuple[float, float]) -> None:
        """Record an obstacle the robot touched but may never have seen (too low, too near)."""
        self.bumped |= self.spec.disc(point_xy, self.spec.resolution)
        self.occupied |= self.bumped

    @property
    def free(self) -> np.ndarray:
        return (self.floor_seen | self.stood) & ~self.occupied

    def clearance(self) -> np.ndarray:
        """Distance in metres from each cell to the nearest occupied cell."""
        return ndimage.distance_transform_edt(~self.occupied) * self.spec.resolution

    def traversable(self, robot_xy: tuple[float, float], clearance: np.ndarray | None = None,
                    squeeze_m: float = 0.0) -> np.ndarray:
        """Free cells farther than the robot's radius (less ``squeeze_m``) from every occupied cell,
        and a way out.

        The robot may stand closer to an obstacle than that (the world checks its true shape, and
        it may have bumped into something it never saw). Around where it stands, cells are open as
        long as they are no closer to an obstacle than the robot is now, so it can back away but
        not push on. ``squeeze_m`` lets a move try gaps that look narrower than the robot on the
        map: its obstacles stand up to a surface band (``surface_tsdf`` of the truncation) fatter
        than they are.
        """
        clearance = self.clearance() if clearance is None else clearance
        radius = self.config.robot_radius - squeeze_m
        row, col = self.spec.to_cell(np.asarray(robot_xy))
        inside = self.spec.inside(np.array([row, col]))
        here_clearance = float(clearance[row, col]) if inside else 0.0
        around = self.spec.disc(robot_xy, radius + self.spec.resolution)
        way_out = around & (clearance >= min(here_clearance, radius))
        return self.free & ((clearance > radius) | way_out)

    def free_area_m2(self) -> float:
        return float(self.free.sum()) * self.spec.resolution**2
