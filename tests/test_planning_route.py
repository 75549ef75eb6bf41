"""Routes for the base over the robot's map: around what stands between it and a stand."""

from __future__ import annotations

import numpy as np

from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.planning.paths import path_length
from agent.planning.route import routes_from


def _room_with_a_cabinet() -> ExplorationMap:
    """A 6 x 6 m room seen whole, walls round it, a 1.2 x 0.6 m cabinet in its middle at y 0..0.6."""
    world_map = ExplorationMap((0.0, 0.0), OccupancyConfig(size_m=8))
    spec = world_map.spec
    rows, cols = np.indices(spec.shape)
    xy = spec.to_world(np.stack([rows, cols], axis=-1))
    inside = (np.abs(xy[..., 0]) < 3.0) & (np.abs(xy[..., 1]) < 3.0)
    cabinet = (np.abs(xy[..., 0]) < 0.6) & (xy[..., 1] > 0.0) & (xy[..., 1] < 0.6)
    world_map.floor_seen = inside & ~cabinet
    world_map.explored = inside.copy()
    world_map.occupied = ~inside | cabinet
    world_map.stood = np.zeros_like(inside)
    return world_map


def test_a_route_goes_round_the_furniture_a_straight_line_would_cross() -> None:
    behind, before = np.array([0.0, 1.5]), np.array([0.1, -1.0])  # either side of the cabinet
    routes = routes_from(_room_with_a_cabinet(), behind)
    assert routes.reaches(before)
    path = routes.to(before)
    assert np.allclose(path[0], behind) and np.allclose(path[-1], before)
    assert path_length(path) > 1.2 * np.linalg.norm(before - behind)
    dense = np.vstack([np.linspace(a, b, 20) for a, b in zip(path[:-1], path[1:])])
    assert not np.any((np.abs(dense[:, 0]) < 0.6 + 0.25) & (dense[:, 1] > -0.25) & (dense[:, 1] < 0.85))


def test_places_in_furniture_against_walls_or_off_the_map_are_not_reached() -> None:
    routes = routes_from(_room_with_a_cabinet(), np.array([0.0, -1.5]))
    for xy in ((0.0, 0.3), (0.0, 0.75), (2.9, 0.0), (3.5, 0.0), (9.0, 9.0)):
        assert not routes.reaches(np.array(xy)), xy
