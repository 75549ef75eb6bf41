"""The fields planners derive from the robot's map, computed once per state of the map.

Choosing a frontier, heading for storage and planning the way to a stand each need the map's
clearance (metres from every cell to the nearest obstacle) and a distance field of path costs
from the robot over the cells it may drive. The map changes only when a frame is fused into it or
the base reports where it drove or bumped (`ExplorationMap.revision` counts those changes), so
`MapFields` keeps what it computed for the map's current revision and hands the same arrays to
every caller until the map changes. Callers only read what they are handed.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from agent.mapping.occupancy import ExplorationMap
from agent.planning.paths import DistanceField, clearance_cost, distance_field

if TYPE_CHECKING:
    from agent.planning.frontier_plan import ExploreConfig


def drive_field(world_map: ExplorationMap, robot_xy: tuple[float, float], clearance: np.ndarray,
                config: ExploreConfig, squeeze_m: float = 0.0) -> tuple[DistanceField, np.ndarray]:
    """Path costs from the robot over the cells it may drive (kept off walls where there is room).

    Args:
        world_map: the robot's map.
        robot_xy: where the robot stands (world x, y).
        clearance: ``world_map.clearance()``, which callers often need too.
        config: how far paths keep off obstacles and what coming nearer costs.
        squeeze_m: see `ExplorationMap.traversable`.

    Returns:
        The distance field and the cells it was computed over.
    """
    start = tuple(int(v) for v in world_map.spec.to_cell(np.asarray(robot_xy)))
    cell_cost = clearance_cost(clearance, world_map.config.robot_radius, config.comfort_m, config.obstacle_cost)
    traversable = world_map.traversable(robot_xy, clearance, squeeze_m)
    return distance_field(world_map.spec, traversable, start, cell_cost), traversable


class MapFields:
    """Clearance and drive fields of one map, kept until the map changes."""

    def __init__(self) -> None:
        self._map: ExplorationMap | None = None
        self._revision = -1
        self._clearance: np.ndarray | None = None
        self._fields: dict[tuple[float, float, float, float, float], tuple[DistanceField, np.ndarray]] = {}

    def clearance(self, world_map: ExplorationMap) -> np.ndarray:
        """``world_map.clearance()`` as the map stands now, computed once per revision.

        Args:
            world_map: the robot's map.

        Returns:
            Metres from each cell to the nearest occupied cell (not to be written to).
        """
        self._follow(world_map)
        if self._clearance is None:
            self._clearance = world_map.clearance()
        return self._clearance

    def drive_field(self, world_map: ExplorationMap, robot_xy: tuple[float, float], config: ExploreConfig,
                    squeeze_m: float = 0.0) -> tuple[DistanceField, np.ndarray]:
        """`drive_field` over the map as it stands now, computed once per revision, start and settings.

        Args:
            world_map: the robot's map.
            robot_xy: where the robot stands (world x, y).
            config: how far paths keep off obstacles and what coming nearer costs.
            squeeze_m: see `ExplorationMap.traversable`.

        Returns:
            The distance field and the cells it was computed over (not to be written to).
        """
        xy = (float(robot_xy[0]), float(robot_xy[1]))
        key = (*xy, float(squeeze_m), float(config.comfort_m), float(config.obstacle_cost))
        clearance = self.clearance(world_map)
        if key not in self._fields:
            self._fields[key] = drive_field(world_map, xy, clearance, config, squeeze_m)
        return self._fields[key]

    def _follow(self, world_map: ExplorationMap) -> None:
        """Forget what was computed for another map or an earlier revision of this one."""
        if world_map is not self._map or world_map.revision != self._revision:
            self._map, self._revision = world_map, world_map.revision
            self._clearance = None
            self._fields = {}
