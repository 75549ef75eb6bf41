"""The 2D maps the planners use, derived from the TSDF and the camera's narrow view.

- occupied: a column holds a surface voxel between ``obstacle_min_z`` and the robot's height,
  within a cell of where some depth pixel has landed at that height, unless the robot has driven
  through it;
- floor seen: a column holds a surface voxel at floor height;
- free: floor seen and not occupied, or near a pose the robot has stood on;
- explored: hit by a narrow-view ray (the middle half of the columns, lower half of the rows)
  within the TSDF's range, or near a pose the robot has stood on.

"Near a pose" is the head camera's blind zone (``near_field_radius``): the floor closer than the
lower edge of the image is never in view, yet the robot has just been there. Counting it as free
and explored lets frontiers form at its edge, so a robot that starts facing a wall turns away.

Surface voxels are the TSDF's zero crossings (`agent.mapping.surface`), and each voxel goes to the
2D cell by its integer lattice index: the grid is laid so that voxel samples sit at cell centres,
never on a cell boundary where float rounding would decide the cell. A TSDF averages its views, so
free space seen past a door jamb from one spot and behind the jamb from another averages to
near zero and looks like a surface hanging in the doorway; no depth pixel ever lands there, so
obstacles also need a depth hit in or beside their cell.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from agent.mapping.camera import Intrinsics, back_project, narrow_view_mask
from agent.mapping.grid import GridSpec
from agent.mapping.columns import ColumnBands, SurfaceColumns
from agent.mapping.tsdf import TsdfConfig, TsdfMap

_EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True)
class OccupancyConfig:
    """Heights and thresholds of the 2D projection, in metres unless said otherwise."""

    size_m: float = 48.0  # the largest homes are 22.4 m long, and the robot may start at one end
    resolution: float = 0.1
    floor_band: tuple[float, float] = (-0.12, 0.08)
    obstacle_min_z: float = 0.12
    obstacle_max_z: float = 1.6
    surface_tsdf: float = 1.0  # the most |normalised TSDF| two voxels of a zero crossing may add up to
    robot_radius: float = 0.25
    near_field_radius: float = 1.0  # floor the head camera cannot see around a pose it stood on
    driven_radius: float = 0.15  # around the path the base drove, no obstacle can stand
    tsdf: TsdfConfig = field(default_factory=TsdfConfig)

    def __post_init__(self) -> None:
        voxel = self.tsdf.voxel_size
        if not (np.isfinite(voxel) and voxel > 0):
            raise ValueError(f"map.tsdf.voxel_size: {voxel!r} must be a positive number of metres")
        ratio = self.resolution / voxel if np.isfinite(self.resolution) and self.resolution > 0 else 0.0
        if ratio < 1 or abs(ratio - round(ratio)) > 1e-6:
            raise ValueError(f"map.resolution: {self.resolution!r} must be a whole multiple (1, 2, …) of "
                             f"map.tsdf.voxel_size ({voxel:g} m), so every voxel falls in one cell")
        if not (np.isfinite(self.size_m) and self.resolution <= self.size_m <= 1000):
            raise ValueError(f"map.size_m: {self.size_m!r} must be between map.resolution and 1000 m")


def lattice_grid(centre_xy: tuple[float, float], config: OccupancyConfig) -> GridSpec:
    """A square grid of ``config.size_m`` around ``centre_xy`` whose cell centres lie on the voxel
    lattice: its origin is half a voxel off a lattice line, so no voxel sits on a cell boundary.

    Args:
        centre_xy: the grid's centre (world, m).
        config: the map's settings (size, resolution, voxel size).

    Returns:
        The grid.
    """
    voxel = config.tsdf.voxel_size
    cells = int(np.ceil(config.size_m / config.resolution))
    half = cells * config.resolution / 2
    origin = tuple(float(np.round((c - half) / voxel) * voxel - voxel / 2) for c in centre_xy)
    return GridSpec((origin[0], origin[1]), config.resolution, (cells, cells))


class ExplorationMap:
    """The robot's picture of the home so far: TSDF plus the 2D free, occupied and explored grids.

    Args:
        start_xy: where the robot starts (the grid's centre).
        config: the map's settings.
    """

    def __init__(self, start_xy: tuple[float, float], config: OccupancyConfig = OccupancyConfig()) -> None:
        self.config = config
        self.spec = lattice_grid(start_xy, config)
        self.tsdf = TsdfMap(config.tsdf)
        self.columns = SurfaceColumns(self.spec, self.tsdf, ColumnBands(
            config.floor_band, (config.obstacle_min_z, config.obstacle_max_z), config.surface_tsdf,
            0.5 / config.tsdf.trunc_voxels))
        self.explored = np.zeros(self.spec.shape, dtype=bool)
        self.stood = np.zeros(self.spec.shape, dtype=bool)
        self.driven = np.zeros(self.spec.shape, dtype=bool)
        self.floor_seen = np.zeros(self.spec.shape, dtype=bool)
        self.occupied = np.zeros(self.spec.shape, dtype=bool)
        self.bumped = np.zeros(self.spec.shape, dtype=bool)
        self.obstacle_hits = np.zeros(self.spec.shape, dtype=bool)  # a depth pixel landed at obstacle height
        self._near_hits = np.zeros(self.spec.shape, dtype=bool)  # obstacle_hits widened by a cell
        self.revision = 0  # counts the changes below, so that what is derived from the map knows when to renew

    def integrate(self, depth: np.ndarray, intrinsics: Intrinsics, camera_to_world: np.ndarray,
                  robot_xy: tuple[float, float]) -> None:
        """Fuse one frame taken with the robot at ``robot_xy``.

        Args:
            depth: the linear depth image (m; 0 = no return).
            intrinsics: the camera's intrinsics.
            camera_to_world: the camera's world pose (4x4).
            robot_xy: where the robot stood.
        """
        config = self.config
        self.revision += 1
        self.columns.renew(self.tsdf.integrate(depth, intrinsics, camera_to_world))
        # Only what the TSDF takes in may count as explored: a cell seen beyond its range could
        # never turn free, and a frontier that reaches it would vanish for good.
        in_range = (depth > 0) & (depth <= config.tsdf.depth_max)
        points = back_project(depth, intrinsics, camera_to_world, in_range)
        narrow = narrow_view_mask(*depth.shape)[in_range]
        at_height = (points[:, 2] >= config.obstacle_min_z) & (points[:, 2] <= config.obstacle_max_z)
        self._mark_hits(points[at_height])
        self.floor_seen = self.columns.floor.copy()
        self.occupied = (self.columns.obstacle & self._near_hits & ~self.driven) | self.bumped
        window = self.spec.disc_window(robot_xy, config.near_field_radius)
        if window is not None:
            self.stood[window[0]] |= window[1] & ~self.occupied[window[0]]
        self._mark(self.explored, points[narrow])
        self.explored |= self.stood

    def _mark(self, grid: np.ndarray, points: np.ndarray) -> None:
        """Set the cells of ``grid`` that the points (N, 3) fall in."""
        cells = self.spec.to_cell(points[:, :2])
        cells = cells[self.spec.inside(cells)]
        grid[cells[:, 0], cells[:, 1]] = True

    def _mark_hits(self, points: np.ndarray) -> None:
        """Set the cells of ``obstacle_hits`` the points (N, 3) fall in, and in ``_near_hits`` the
        same cells widened by one (dilating just the window the points fall in)."""
        cells = self.spec.to_cell(points[:, :2])
        cells = cells[self.spec.inside(cells)]
        if len(cells) == 0:
            return
        self.obstacle_hits[cells[:, 0], cells[:, 1]] = True
        low = np.maximum(cells.min(axis=0) - 1, 0)
        high = np.minimum(cells.max(axis=0) + 2, self.spec.shape)
        window = np.zeros(tuple(high - low), dtype=bool)
        window[cells[:, 0] - low[0], cells[:, 1] - low[1]] = True
        self._near_hits[low[0]:high[0], low[1]:high[1]] |= ndimage.binary_dilation(window, structure=_EIGHT)

    def mark_driven(self, path_xy: np.ndarray) -> None:
        """Record the polyline (K, 2) the base drove along: no obstacle stands where the base has
        been, so no later frame may close the gap it went through.

        Args:
            path_xy: the waypoints driven, in order, in world metres.
        """
        self.revision += 1
        path = np.asarray(path_xy, dtype=float).reshape(-1, 2)
        step = self.spec.resolution / 2
        for start, end in zip(path[:-1], path[1:]):
            samples = max(int(np.ceil(np.hypot(*(end - start)) / step)), 1)
            t = np.linspace(0.0, 1.0, samples + 1)[:, None]
            self._mark_discs(self.driven, start + t * (end - start), self.config.driven_radius)
        if len(path) == 1:
            self._mark_discs(self.driven, path[:1], self.config.driven_radius)
        self.occupied &= ~self.driven | self.bumped

    def _mark_discs(self, grid: np.ndarray, centres_xy: np.ndarray, radius_m: float) -> None:
        """Set the cells of ``grid`` within ``radius_m`` of any of the points (N, 2)."""
        window = self.spec.discs_window(centres_xy, radius_m)
        if window is not None:
            grid[window[0]] |= window[1]

    def mark_contact(self, point_xy: tuple[float, float]) -> None:
        """Record an obstacle the robot touched but may never have seen (too low, too near).

        Args:
            point_xy: where it touched (world, m).
        """
        self.revision += 1
        self._mark_discs(self.bumped, np.asarray(point_xy, dtype=float), self.spec.resolution)
        self.occupied |= self.bumped

    @property
    def free(self) -> np.ndarray:
        return (self.floor_seen | self.stood) & ~self.occupied

    def clearance(self) -> np.ndarray:
        """Distance in metres from each cell to the nearest occupied cell.

        Returns:
            The distances, one per cell.
        """
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

        Args:
            robot_xy: where the robot stands.
            clearance: `clearance`, when already computed.
            squeeze_m: how much narrower than the robot a gap may look.

        Returns:
            A boolean grid of the cells the robot may move through.
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
        """The area of the cells seen free (m²).

        Returns:
            The area.
        """
        return float(self.free.sum()) * self.spec.resolution**2
