"""The 2D map of an analytic box room: exact ray-cast depth, so every missing cell is the map's fault.

The room's interior is 6 x 4 m with 0.1 m walls and a doorway in the east wall; beyond the doorway
there is nothing a ray can hit, so the doorway is the one way on. The robot turns on the spot in
its middle. Grid origins on the voxel lattice (a start on round coordinates) once lost a third of
the free floor and the doorway's frontier, so every test runs on and off the lattice.
"""

from __future__ import annotations

import numpy as np
import pytest

from agent.app.config import ConfigError, load_config
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.planning.frontier_plan import reachable_frontiers
from boxroom import BoxRoom, survey, walls_with_doorway

ROOM = (0.0, 0.0, 6.0, 4.0)
STARTS = [(3.0, 2.0), (3.05, 2.03), (2.97, 1.51), (3.1, 2.1)]
MIN_IOU = 0.98


def _room(door_y: tuple[float, float]) -> BoxRoom:
    x0, y0, x1, y1 = ROOM
    return BoxRoom((x0, y0, x1 + 0.1, y1), walls_with_doorway(x0, y0, x1, y1, door_y))


def _cell_centres(world_map: ExplorationMap) -> np.ndarray:
    rows, cols = np.indices(world_map.spec.shape)
    return world_map.spec.to_world(np.stack([rows, cols], axis=-1))


def _inside_room(world_map: ExplorationMap) -> np.ndarray:
    """Cells that lie wholly inside the room's interior (a cell a wall cuts is rightly occupied)."""
    centres, half = _cell_centres(world_map), world_map.spec.resolution / 2 - 1e-6
    x0, y0, x1, y1 = ROOM
    return ((centres[..., 0] - half > x0) & (centres[..., 0] + half < x1)
            & (centres[..., 1] - half > y0) & (centres[..., 1] + half < y1))


@pytest.mark.parametrize("start", STARTS)
def test_free_cells_cover_the_floor_the_camera_saw(start: tuple[float, float]) -> None:
    world_map = ExplorationMap(start, OccupancyConfig(size_m=16))
    hits = survey(_room((1.5, 2.5)), world_map, start)
    seen = np.zeros(world_map.spec.shape, dtype=bool)
    cells = world_map.spec.to_cell(hits)
    seen[cells[:, 0], cells[:, 1]] = True
    truth = (seen | world_map.stood) & _inside_room(world_map)
    free = world_map.free & _inside_room(world_map)
    iou = (free & truth).sum() / (free | truth).sum()
    assert iou >= MIN_IOU, f"free cells cover the seen floor with IoU {iou:.3f} (start {start})"
    assert not (world_map.free & ~_inside_room(world_map) & (_cell_centres(world_map)[..., 0] < 5.9)).any(), \
        "the map calls cells free beyond the west, south or north walls"


@pytest.mark.parametrize("start", STARTS)
@pytest.mark.parametrize("door_y", [(1.5, 2.5), (1.55, 2.45)])
def test_the_doorway_is_the_one_frontier_and_faces_out(start: tuple[float, float], door_y: tuple[float, float]) -> None:
    world_map = ExplorationMap(start, OccupancyConfig(size_m=16))
    survey(_room(door_y), world_map, start)
    frontiers = reachable_frontiers(world_map, start).frontiers
    assert len(frontiers) == 1, f"{len(frontiers)} frontiers, expected the doorway's alone"
    centre = world_map.spec.to_world(np.asarray(frontiers[0].centre))
    assert abs(centre[0] - 6.05) <= 0.15 and abs(centre[1] - sum(door_y) / 2) <= 0.15, f"frontier at {centre}"
    assert frontiers[0].normal @ np.array([1.0, 0.0]) > 0.95, f"normal {frontiers[0].normal} does not point out"


def test_walls_are_one_voxel_thick_so_a_narrow_doorway_stays_passable() -> None:
    """An 0.8 m doorway seen from 2 m: the robot (radius 0.25 m) can plan through it."""
    x0, y0, x1, y1 = ROOM
    beyond = BoxRoom((x0, y0, x1 + 3.0, y1), walls_with_doorway(x0, y0, x1, y1, (1.6, 2.4)))
    start = (4.0, 2.0)
    world_map = ExplorationMap(start, OccupancyConfig(size_m=16))
    survey(beyond, world_map, start, headings=1)
    traversable = world_map.traversable(start)
    row, col = world_map.spec.to_cell(np.array([6.05, 2.0]))
    assert traversable[row, col], "the middle of a 0.8 m doorway is not traversable"
    occupied_x = _cell_centres(world_map)[world_map.occupied & (np.abs(_cell_centres(world_map)[..., 1] - 1.0) < 0.05)]
    assert set(np.round(occupied_x[:, 0], 2)) <= {6.0, 6.1}, f"the east wall spans x = {sorted(set(np.round(occupied_x[:, 0], 2)))}"


def test_cells_the_robot_drove_through_are_never_occupied_afterwards() -> None:
    start = (1.0, 2.0)
    world_map = ExplorationMap(start, OccupancyConfig(size_m=16))
    world_map.mark_driven(np.array([[1.0, 2.0], [3.0, 2.0]]))
    crate = BoxRoom((0.0, 0.0, 6.0, 4.0), [(2.0, 1.5, 0.0, 2.3, 2.5, 0.5)])  # stands across the path
    survey(crate, world_map, start, headings=1)
    row, col = world_map.spec.to_cell(np.array([2.0, 2.0]))
    assert not world_map.occupied[row, col], "a cell on the driven path became occupied"
    row, col = world_map.spec.to_cell(np.array([2.0, 1.6]))
    assert world_map.occupied[row, col], "the crate's face beside the path is missing"


def test_cell_centres_lie_on_the_voxel_lattice() -> None:
    for start in STARTS:
        world_map = ExplorationMap(start, OccupancyConfig(size_m=16))
        offsets = world_map.spec.to_world(np.array([[0, 0], [7, 11]])) / world_map.config.tsdf.voxel_size
        assert np.allclose(offsets, np.round(offsets), atol=1e-9), f"cell centres off the lattice for {start}"


@pytest.mark.parametrize("value, problem", [("0", r"must lie in \(0, 10\]"), ("0.05", "whole multiple"), ("0.15", "whole multiple")])
def test_a_map_resolution_that_splits_voxels_is_refused_by_name(value: str, problem: str) -> None:
    with pytest.raises(ConfigError, match=rf"map\.resolution.*{problem}"):
        load_config(None, [f"map.resolution={value}"])


def test_floor_seen_far_away_at_a_grazing_angle_is_free() -> None:
    """A 12 m hall looked down from one end: the floor 3 to 6 m ahead (depth_max) is free too."""
    hall = BoxRoom((0.0, 0.0, 12.0, 4.0), walls_with_doorway(0.0, 0.0, 12.0, 4.0, (4.0, 4.0)))
    start = (0.6, 2.0)
    world_map = ExplorationMap(start, OccupancyConfig(size_m=30))
    hits = survey(hall, world_map, start, headings=1)
    far = hits[(np.hypot(*(hits - np.asarray(start)).T) > 3.0) & (np.hypot(*(hits - np.asarray(start)).T) < 5.8)
               & (hits[:, 1] > 0.2) & (hits[:, 1] < 3.8)]
    cells = world_map.spec.to_cell(far)
    share = world_map.free[cells[:, 0], cells[:, 1]].mean()
    assert len(far) > 1000 and share >= 0.98, f"{share:.0%} of the floor seen 3-6 m away is free"


def test_what_lies_beyond_the_tsdf_range_stays_unexplored_so_the_hall_keeps_its_frontier() -> None:
    """Floor seen farther than the TSDF integrates (6 m) never turns free: were it explored, the
    frontier down the hall would vanish and the robot would think the hall done."""
    hall = BoxRoom((0.0, 0.0, 12.0, 4.0), walls_with_doorway(0.0, 0.0, 12.0, 4.0, (4.0, 4.0)))
    start = (0.6, 2.0)
    world_map = ExplorationMap(start, OccupancyConfig(size_m=30))
    survey(hall, world_map, start, headings=1)
    beyond = _cell_centres(world_map)[..., 0] > start[0] + world_map.config.tsdf.depth_max + 0.2
    assert not (world_map.explored & beyond).any(), "cells beyond the TSDF's range are marked explored"
    frontiers = reachable_frontiers(world_map, start).frontiers
    ahead = [f for f in frontiers if f.normal @ np.array([1.0, 0.0]) > 0.9]
    assert ahead, "no frontier faces on down the hall"
