"""The 2D floor and obstacle columns, renewed frame by frame where the TSDF changed, equal a
projection of the whole volume made afresh, after every frame of a walk through a real home."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import ndimage

from agent.mapping.camera import Intrinsics
from agent.mapping.columns import ColumnBands, SurfaceColumns
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig, lattice_grid
from agent.mapping.surface import surface_mask
from agent.mapping.tsdf import TsdfConfig
from worlds.robot import CameraConfig
from worlds.sim import World

SEED = 4


def _bands(config: OccupancyConfig) -> ColumnBands:
    return ColumnBands(config.floor_band, (config.obstacle_min_z, config.obstacle_max_z), config.surface_tsdf,
                       0.5 / config.tsdf.trunc_voxels)


def _whole_projection(world_map: ExplorationMap) -> tuple[np.ndarray, np.ndarray]:
    """(floor, obstacle) from every observed voxel open3d lists, the way the map was once made
    each step: all voxels read out, one dense field, cells from the voxels' own positions."""
    grid = world_map.tsdf._grid
    config = world_map.config
    coords, flat = grid.voxel_coordinates_and_flattened_indices()
    tsdf = grid.attribute("tsdf").reshape((-1,))[flat].numpy()
    weight = grid.attribute("weight").reshape((-1,))[flat].numpy()
    seen = weight > 0
    indices = np.rint(coords.numpy()[seen] / config.tsdf.voxel_size).astype(np.int64)
    tsdf = tsdf[seen]
    low = indices.min(axis=0)
    field = np.full(tuple(indices.max(axis=0) - low + 1), np.nan, dtype=np.float32)
    field[tuple((indices - low).T)] = tsdf
    bands = _bands(config)
    on_surface = surface_mask(field, bands.max_pair_tsdf, bands.near_tsdf)[tuple((indices - low).T)]
    points = indices[on_surface] * config.tsdf.voxel_size
    cells = world_map.spec.to_cell(points[:, :2])
    inside = world_map.spec.inside(cells)
    points, cells = points[inside], cells[inside]
    floor = np.zeros(world_map.spec.shape, dtype=bool)
    obstacle = np.zeros(world_map.spec.shape, dtype=bool)
    at_floor = (points[:, 2] >= config.floor_band[0]) & (points[:, 2] <= config.floor_band[1])
    floor[cells[at_floor, 0], cells[at_floor, 1]] = True
    high = (points[:, 2] >= config.obstacle_min_z) & (points[:, 2] <= config.obstacle_max_z)
    obstacle[cells[high, 0], cells[high, 1]] = True
    return floor, obstacle


def _walk(config: OccupancyConfig, frames: int):
    """A map fused from ``frames`` views taken from the middle of each room in turn, the
    heading turning, and the map after each."""
    camera = CameraConfig()
    world = World(camera)
    try:
        scenario = world.reset(SEED)
        intrinsics = Intrinsics(camera.width, camera.height, *camera.intrinsics())
        world_map = ExplorationMap(scenario.start_pose[:2], config)
        rooms = world.home.rooms
        for k in range(frames):
            xmin, ymin, xmax, ymax = rooms[k % len(rooms)].rect
            x, y = (xmin + xmax) / 2, (ymin + ymax) / 2
            world.place((x, y, k * 2.4 % (2 * math.pi)))
            frame = world.observe()
            world_map.integrate(frame.depth, intrinsics, frame.camera_pose, (x, y))
            yield world_map
    finally:
        world.close()


def test_renewed_columns_equal_the_whole_projection_after_every_frame() -> None:
    checked = 0
    for world_map in _walk(OccupancyConfig(), frames=14):
        floor, obstacle = _whole_projection(world_map)
        assert np.array_equal(world_map.columns.floor, floor)
        assert np.array_equal(world_map.columns.obstacle, obstacle)
        assert np.array_equal(world_map.floor_seen, floor)
        checked += 1
    assert checked == 14 and floor.sum() > 500 and obstacle.sum() > 100  # the walk saw several rooms


def test_cells_two_voxels_wide_renew_as_the_whole_volume_does() -> None:
    config = OccupancyConfig(resolution=0.2, tsdf=TsdfConfig(voxel_size=0.1))
    for world_map in _walk(config, frames=6):
        fresh = SurfaceColumns(world_map.spec, world_map.tsdf, _bands(config))
        fresh.renew(world_map.tsdf.blocks())
        assert np.array_equal(world_map.columns.floor, fresh.floor)
        assert np.array_equal(world_map.columns.obstacle, fresh.obstacle)
    assert fresh.floor.sum() > 100


def test_obstacle_hits_are_widened_by_one_cell() -> None:
    for world_map in _walk(OccupancyConfig(), frames=3):
        widened = ndimage.binary_dilation(world_map.obstacle_hits, structure=np.ones((3, 3), dtype=bool))
        assert np.array_equal(world_map._near_hits, widened)
    assert world_map.obstacle_hits.any()


def test_a_frame_that_touches_nothing_changes_nothing() -> None:
    config = OccupancyConfig()
    world_map = ExplorationMap((0.0, 0.0), config)
    columns = SurfaceColumns(lattice_grid((0.0, 0.0), config), world_map.tsdf, _bands(config))
    columns.renew(np.zeros((0, 3), dtype=np.int64))
    assert not columns.floor.any() and not columns.obstacle.any()
    empty = np.zeros((CameraConfig().height, CameraConfig().width), dtype=np.float32)
    camera = CameraConfig()
    world_map.integrate(empty, Intrinsics(camera.width, camera.height, *camera.intrinsics()), np.eye(4), (0.0, 0.0))
    assert not world_map.floor_seen.any() and not world_map.occupied.any()


@pytest.mark.parametrize("resolution", [0.1, 0.3])
def test_the_ring_of_blocks_read_covers_a_cell_and_its_neighbours(resolution: float) -> None:
    config = OccupancyConfig(resolution=resolution)
    columns = SurfaceColumns(lattice_grid((0.0, 0.0), config), ExplorationMap((0.0, 0.0), config).tsdf, _bands(config))
    voxels_per_cell = round(resolution / config.tsdf.voxel_size)
    assert columns._ring * config.tsdf.block_resolution >= voxels_per_cell + 1
