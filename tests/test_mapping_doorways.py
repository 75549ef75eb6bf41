"""Doorways in generated homes stay passable in the robot's map once it has looked through them.

For every doorway of 20 generated homes, the robot stands on its axis 1.5 to 3 m away where the
home leaves it room, looks through, and plans: the floor half a metre past the doorway must be
reachable over the cells its map lets it drive. Doorways are 0.8 m wide or more and the robot's
radius is 0.25 m, so a map that fattens walls or drops floor at range closes them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.mapping.camera import Intrinsics
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.planning.frontier_plan import ExploreConfig
from agent.planning.map_fields import drive_field
from worlds.freespace import clearance
from worlds.robot import CameraConfig
from worlds.sim import World

HOMES = range(20)
STAND_OFF_M = (3.0, 2.5, 2.0, 1.5)
PAST_M = 0.5
LANE_M = 0.35  # the clearance the whole way from the stand to past the doorway must keep


def _axis(doorway) -> np.ndarray:
    """The unit (x, y) across the doorway's wall."""
    return np.array([0.0, 1.0]) if doorway.along == "x" else np.array([1.0, 0.0])


def _lane_is_clear(home, start: np.ndarray, end: np.ndarray) -> bool:
    """Whether a robot could drive straight from ``start`` to ``end`` inside the home: then the
    camera at ``start`` sees the floor along the way, doorway included."""
    for t in np.linspace(0.0, 1.0, int(np.hypot(*(end - start)) / 0.1) + 2):
        x, y = start + t * (end - start)
        if clearance(home, float(x), float(y)) < LANE_M:
            return False
    return True


def _stand(home, doorway, side: float) -> tuple[float, float] | None:
    """The farthest spot on the doorway's axis, up to 3 m before it, with a clear lane through it."""
    centre = np.asarray(doorway.center, dtype=float)
    past = centre + side * PAST_M * _axis(doorway)
    for distance in STAND_OFF_M:
        stand = centre - side * distance * _axis(doorway)
        if home.room_at(*stand) is not None and _lane_is_clear(home, stand, past):
            return float(stand[0]), float(stand[1])
    return None


@pytest.mark.slow
def test_every_doorway_looked_through_is_passable_in_the_map() -> None:
    camera = CameraConfig()
    intrinsics = Intrinsics(camera.width, camera.height, *camera.intrinsics())
    world = World(camera)
    closed: list[str] = []
    checked = 0
    try:
        for seed in HOMES:
            world.reset(seed)
            home = world.home
            for doorway in home.doorways:
                for side in (1.0, -1.0):
                    stand = _stand(home, doorway, side)
                    if stand is None:
                        continue
                    past = np.asarray(doorway.center) + side * PAST_M * _axis(doorway)
                    towards = side * _axis(doorway)
                    world.place((stand[0], stand[1], math.atan2(towards[1], towards[0])))
                    frame = world.observe()
                    world_map = ExplorationMap(stand, OccupancyConfig(size_m=16))
                    world_map.integrate(frame.depth, intrinsics, frame.camera_pose, stand)
                    field, _ = drive_field(world_map, stand, world_map.clearance(), ExploreConfig())
                    cell = tuple(int(v) for v in world_map.spec.to_cell(past))
                    checked += 1
                    if not np.isfinite(field.metres[cell]):
                        closed.append(f"home {seed}: {doorway.width:.2f} m doorway at {doorway.center} from {stand}")
                    break
    finally:
        world.close()
    assert checked >= 60, f"only {checked} doorways could be looked through"
    assert not closed, f"{len(closed)} of {checked} doorways closed in the map:\n" + "\n".join(closed)
