"""Mapping a known room: real PyBullet frames fused into the TSDF give the room's free floor."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.mapping.camera import Intrinsics
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from worlds.robot import CameraConfig
from worlds.sim import World

SEED = 1
#: The share of the room's true free floor the map must find, and the most of what it calls free
#: that may lie on an obstacle. Eight views from one spot cannot see behind furniture or into
#: corners hidden by it, so the map may miss some floor; it must not invent much.
MIN_RECALL = 0.75
MAX_FALSE_FREE = 0.05


@pytest.fixture(scope="module")
def surveyed() -> tuple[World, ExplorationMap, object]:
    """The start room seen from the start pose in eight headings."""
    camera = CameraConfig()
    world = World(camera)
    scenario = world.reset(SEED)
    x, y, _ = scenario.start_pose
    intrinsics = Intrinsics(camera.width, camera.height, *camera.intrinsics())
    world_map = ExplorationMap((x, y), OccupancyConfig())
    for k in range(8):
        world.place((x, y, k * math.pi / 4))
        frame = world.observe()
        world_map.integrate(frame.depth, intrinsics, frame.camera_pose, (x, y))
    room = next(r for r in world.home.rooms if r.contains(x, y))
    yield world, world_map, room
    world.close()


def _room_cells(world_map: ExplorationMap, rect: tuple[float, float, float, float]) -> np.ndarray:
    rows, cols = np.indices(world_map.spec.shape)
    centres = world_map.spec.to_world(np.stack([rows, cols], axis=-1))
    x0, y0, x1, y1 = rect
    wall = 0.1  # the interior ends half a wall thickness inside the room's centre-line rectangle
    return ((centres[..., 0] > x0 + wall) & (centres[..., 0] < x1 - wall)
            & (centres[..., 1] > y0 + wall) & (centres[..., 1] < y1 - wall))


def _on_obstacles(world_map: ExplorationMap, world: World) -> np.ndarray:
    rows, cols = np.indices(world_map.spec.shape)
    centres = world_map.spec.to_world(np.stack([rows, cols], axis=-1))
    blocked = np.zeros(world_map.spec.shape, dtype=bool)
    for x0, y0, x1, y1 in world.home.obstacles():
        blocked |= (centres[..., 0] >= x0) & (centres[..., 0] <= x1) & (centres[..., 1] >= y0) & (centres[..., 1] <= y1)
    return blocked


def test_free_area_of_the_start_room_is_found(surveyed) -> None:
    world, world_map, room = surveyed
    inside = _room_cells(world_map, room.rect)
    truly_free = inside & ~_on_obstacles(world_map, world)
    found = world_map.free & truly_free
    recall = found.sum() / truly_free.sum()
    assert recall >= MIN_RECALL, f"the map found {recall:.0%} of the room's free floor"


def test_little_of_what_the_map_calls_free_is_an_obstacle(surveyed) -> None:
    world, world_map, room = surveyed
    free = world_map.free & _room_cells(world_map, room.rect)
    false_free = (free & _on_obstacles(world_map, world)).sum() / free.sum()
    assert false_free <= MAX_FALSE_FREE, f"{false_free:.1%} of the mapped free floor is an obstacle"


def test_walls_of_the_room_are_occupied(surveyed) -> None:
    world, world_map, room = surveyed
    x0, y0, x1, y1 = room.rect
    row, col = world_map.spec.to_cell(np.array([(x0 + x1) / 2, y1]))
    assert world_map.occupied[row - 1 : row + 2, col - 3 : col + 4].any(), "the far wall is missing"
