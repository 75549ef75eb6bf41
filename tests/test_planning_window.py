"""Planning on the map's known window gives what planning on the whole grid gives, to the bit:
clearance, drive fields and their paths, routes, frontiers, and the free cells prompt points are
drawn from.

Maps are fused from real PyBullet frames (the start room seen in eight headings, the base then
driving a little way) into grids of several sizes, one of them so small that the room runs off
its edges, and drawn by hand (no obstacle at all, frontiers along the grid's edge). The whole-grid
answers come from the same functions run without a window, and from the definitions written out
here for frontiers.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy import ndimage

from agent.mapping.camera import Intrinsics
from agent.mapping.grid import GridSpec
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.planning.frontier import cluster_frontiers, frontier_cells
from agent.planning.frontier_plan import ExploreConfig, reachable_frontiers
from agent.planning.map_fields import WINDOW_MARGIN_M, MapFields, known_window
from agent.planning.paths import clearance_cost, distance_field
from agent.planning.prompt_points import PromptPointConfig, visible_free_cells
from agent.planning.route import Routes, routes_from
from agent.planning.window import Window
from worlds.robot import CameraConfig
from worlds.sim import World

SEED = 1
CONFIG = ExploreConfig()


@pytest.fixture(scope="module")
def frames() -> tuple[tuple[float, float], list[tuple[np.ndarray, np.ndarray]], Intrinsics]:
    """The start (x, y) and eight frames (depth, camera pose) taken there, one per heading."""
    camera = CameraConfig()
    world = World(camera)
    x, y, _ = world.reset(SEED).start_pose
    taken = []
    for k in range(8):
        world.place((x, y, k * math.pi / 4))
        frame = world.observe()
        taken.append((frame.depth, frame.camera_pose))
    world.close()
    return (x, y), taken, Intrinsics(camera.width, camera.height, *camera.intrinsics())


def fused(frames, centre_offset_xy: tuple[float, float] = (0.0, 0.0), size_m: float = 48.0) -> ExplorationMap:
    """The frames fused into a map of ``size_m`` centred ``centre_offset_xy`` off the start, the
    base then driving half a metre along +x (or what of it is free) and bumping into something."""
    (x, y), taken, intrinsics = frames
    world_map = ExplorationMap((x + centre_offset_xy[0], y + centre_offset_xy[1]), OccupancyConfig(size_m=size_m))
    for depth, pose in taken:
        world_map.integrate(depth, intrinsics, pose, (x, y))
    world_map.mark_driven(np.array([[x, y], [x + 0.5, y]]))
    world_map.mark_contact((x + 0.8, y + 0.3))
    return world_map


def frontier_oracle(reachable: np.ndarray, explored: np.ndarray, occupied: np.ndarray, least: int) -> np.ndarray:
    """`frontier_cells` by its definition over the whole grid (nothing beyond the grid counts)."""
    open_unknown = np.pad(~explored & ~occupied, 1)
    rows, cols = reachable.shape
    counts = sum(open_unknown[1 + dr : 1 + dr + rows, 1 + dc : 1 + dc + cols].astype(int)
                 for dr in (-1, 0, 1) for dc in (-1, 0, 1) if (dr, dc) != (0, 0))
    return reachable & (counts >= least)


def cluster_oracle(mask: np.ndarray, explored: np.ndarray, occupied: np.ndarray, min_size: int) -> list:
    """(cells, centre, normal) of each cluster, one whole-grid mask per label, one cluster at a time."""
    labels, count = ndimage.label(mask, structure=np.ones((3, 3), dtype=bool))
    found = []
    for index in range(1, count + 1):
        cells = np.argwhere(labels == index)
        if len(cells) >= min_size:
            mean = cells.mean(axis=0)
            centre = tuple(int(v) for v in cells[np.argmin(np.hypot(*(cells - mean).T))])
            found.append((cells, centre, normal_oracle(cells, ~explored & ~occupied)))
    return found


def normal_oracle(cells: np.ndarray, open_unknown: np.ndarray) -> np.ndarray:
    """The mean step from the cells to their open unknown neighbours on the grid, as unit (x, y)."""
    rows, cols = open_unknown.shape
    total = np.zeros(2)
    for dr, dc in [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if (dr, dc) != (0, 0)]:
        r, c = cells[:, 0] + dr, cells[:, 1] + dc
        ok = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
        total += np.count_nonzero(open_unknown[r[ok], c[ok]]) * np.array([dc, dr]) / np.hypot(dc, dr)
    norm = np.hypot(*total)
    return total / norm if norm > 0 else np.array([1.0, 0.0])


def assert_same_clusters(frontiers: list, expected: list) -> None:
    assert len(frontiers) == len(expected)
    for frontier, (cells, centre, normal) in zip(frontiers, expected):
        np.testing.assert_array_equal(frontier.cells, cells)
        assert frontier.cells.dtype == cells.dtype
        assert frontier.centre == centre
        np.testing.assert_array_equal(frontier.normal, normal)


def whole_grid_field(world_map: ExplorationMap, robot_xy: tuple[float, float], squeeze_m: float = 0.0):
    """The drive field and traversable cells as computed over the whole grid, with its clearance."""
    clearance = world_map.clearance()
    traversable = world_map.traversable(robot_xy, clearance, squeeze_m)
    cost = clearance_cost(clearance, world_map.config.robot_radius, CONFIG.comfort_m, CONFIG.obstacle_cost)
    start = tuple(int(v) for v in world_map.spec.to_cell(np.asarray(robot_xy)))
    return distance_field(world_map.spec, traversable, start, cost), traversable


def assert_planning_as_on_the_whole_grid(world_map: ExplorationMap, robot_xy: tuple[float, float]) -> None:
    """Clearance, drive fields, paths, routes and frontiers from `MapFields` equal the whole grid's."""
    fields = MapFields()
    clearance = fields.clearance(world_map)
    whole = world_map.clearance()
    window = known_window(world_map)
    if world_map.occupied.any():
        inside = window.paste(np.ones((window.bottom - window.top, window.right - window.left), dtype=bool), False)
        np.testing.assert_array_equal(clearance[inside], whole[inside])
        assert np.isinf(clearance[~inside]).all() and (whole[~inside] > WINDOW_MARGIN_M).all()
    else:  # the whole grid's, which is not +inf far away
        np.testing.assert_array_equal(clearance, whole)
    for squeeze_m in (0.0, 0.1):
        field, traversable = fields.drive_field(world_map, robot_xy, CONFIG, squeeze_m)
        expected, expected_traversable = whole_grid_field(world_map, robot_xy, squeeze_m)
        np.testing.assert_array_equal(traversable, expected_traversable)
        np.testing.assert_array_equal(field.metres, expected.metres)
        reachable = np.argwhere(np.isfinite(field.metres))
        assert len(reachable) > 100
        for cell in map(tuple, reachable[::7]):
            np.testing.assert_array_equal(field.path_to(cell), expected.path_to(cell))
    expected = whole_grid_field(world_map, robot_xy)[0]
    routes = routes_from(world_map, np.asarray(robot_xy), CONFIG, fields=fields)
    expected_routes = Routes(expected, np.asarray(robot_xy), whole, world_map.config.robot_radius)
    np.testing.assert_array_equal(routes.standable(), expected_routes.standable())
    rows, cols = np.indices(world_map.spec.shape)
    for xy in world_map.spec.to_world(np.stack([rows, cols], axis=-1)[::3, ::3].reshape(-1, 2)):
        assert routes.unblocked(xy) == expected_routes.unblocked(xy)
        assert routes.reaches(xy) == expected_routes.reaches(xy)
    candidates = reachable_frontiers(world_map, robot_xy, CONFIG, fields)
    mask = frontier_oracle(np.isfinite(expected.metres), world_map.explored, world_map.occupied,
                           CONFIG.min_unexplored_neighbours)
    expected_frontiers = [f for f in cluster_oracle(mask, world_map.explored, world_map.occupied,
                                                    CONFIG.min_frontier_size)
                          if expected.metres[f[1]] >= CONFIG.min_frontier_distance_m]
    assert candidates.frontiers, "the room seen from one spot has frontiers"
    assert_same_clusters(candidates.frontiers, expected_frontiers)
    np.testing.assert_array_equal(candidates.distances_m, [expected.metres[f[1]] for f in expected_frontiers])


def test_a_fused_room_plans_as_on_the_whole_grid(frames) -> None:
    world_map = fused(frames)
    window = known_window(world_map)
    assert (window.bottom - window.top) * (window.right - window.left) < world_map.explored.size / 4
    assert_planning_as_on_the_whole_grid(world_map, frames[0])


@pytest.mark.parametrize(("size_m", "offset_xy"), [(6.0, (0.0, 0.0)), (6.0, (-1.8, 0.8)), (8.0, (0.0, 3.5))])
def test_a_room_running_off_the_grid_plans_as_on_the_whole_grid(frames, size_m, offset_xy) -> None:
    """Grids smaller than what the robot sees, centred on it or off it (the robot near an edge)."""
    world_map = fused(frames, offset_xy, size_m)
    edges = np.concatenate([world_map.explored[[0, -1], :].ravel(), world_map.explored[:, [0, -1]].ravel()])
    assert edges.any(), "the map reaches the grid's edge"
    assert_planning_as_on_the_whole_grid(world_map, frames[0])


@pytest.mark.parametrize(("size_m", "offset_xy"), [(48.0, (0.0, 0.0)), (6.0, (-1.8, 0.8))])
def test_prompt_point_candidates_are_the_whole_grids(frames, size_m, offset_xy) -> None:
    """Free cells in range are looked for around the robot only: the same cells, in the same order."""
    world_map = fused(frames, offset_xy, size_m)
    robot_xy, taken, intrinsics = frames
    near = PromptPointConfig(min_distance_m=0.5, max_distance_m=2.5)
    for depth, pose in taken:
        xy, pixels = visible_free_cells(world_map, robot_xy, depth, intrinsics, pose, near)
        all_xy, all_pixels = visible_free_cells(world_map, robot_xy, depth, intrinsics, pose,
                                                replace(near, max_distance_m=1000.0))
        kept = np.hypot(all_xy[:, 0] - robot_xy[0], all_xy[:, 1] - robot_xy[1]) <= near.max_distance_m
        np.testing.assert_array_equal(xy, all_xy[kept])
        np.testing.assert_array_equal(pixels, all_pixels[kept])
        assert len(xy) > 0


def test_a_map_with_no_obstacle_plans_as_on_the_whole_grid() -> None:
    """Nothing occupied: the distance transform has nothing to measure to."""
    world_map = ExplorationMap((0.0, 0.0), OccupancyConfig(size_m=12.0))
    xy = world_map.spec.to_world(np.stack(np.indices(world_map.spec.shape), axis=-1))
    world_map.floor_seen = (np.abs(xy[..., 0]) < 2.0) & (np.abs(xy[..., 1]) < 1.5)
    world_map.explored = world_map.floor_seen.copy()
    assert_planning_as_on_the_whole_grid(world_map, (0.3, -0.2))


def test_the_field_of_a_window_is_the_whole_grids_with_ties_alike() -> None:
    """Open floor with scattered posts, whose many equal-cost paths must be broken alike."""
    rng = np.random.default_rng(3)
    spec = GridSpec((0.0, 0.0), 0.1, (60, 60))
    traversable = np.zeros(spec.shape, dtype=bool)
    traversable[10:45, 5:50] = rng.random((35, 45)) > 0.15
    window = Window.bounding(traversable, margin=0)
    start = (20, 20)
    field = distance_field(spec, window.crop(traversable), start, window=window)
    expected = distance_field(spec, traversable, start)
    np.testing.assert_array_equal(field.metres, expected.metres)
    for cell in map(tuple, np.argwhere(np.isfinite(expected.metres))):
        np.testing.assert_array_equal(field.path_to(cell), expected.path_to(cell))
    with pytest.raises(ValueError, match="start cell"):
        distance_field(spec, window.crop(traversable), (2, 2), window=window)


@pytest.mark.parametrize("seed", range(6))
def test_frontiers_of_drawn_maps_are_the_whole_grids(seed: int) -> None:
    """Blobs of explored floor, some cut by the grid's edge, with walls in them."""
    rng = np.random.default_rng(seed)
    shape = (60, 80)
    explored = ndimage.gaussian_filter(rng.random(shape), 3.0) > 0.5
    occupied = explored & (rng.random(shape) > 0.9)
    reachable = explored & ~occupied & (rng.random(shape) > 0.05)
    if seed % 2:  # reachable cells on the grid's edge
        reachable[:, 0] = reachable[-1, :] = True
    mask = frontier_cells(reachable, explored, occupied, 2)
    np.testing.assert_array_equal(mask, frontier_oracle(reachable, explored, occupied, 2))
    assert mask.any()
    spec = GridSpec((0.0, 0.0), 0.1, shape)
    for min_size in (1, 3):
        assert_same_clusters(cluster_frontiers(spec, mask, explored, occupied, min_size),
                             cluster_oracle(mask, explored, occupied, min_size))


def test_nothing_reachable_gives_no_frontier() -> None:
    empty = np.zeros((30, 40), dtype=bool)
    assert not frontier_cells(empty, empty, empty).any()
    assert cluster_frontiers(GridSpec((0.0, 0.0), 0.1, empty.shape), empty, empty, empty) == []
