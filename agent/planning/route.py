"""Paths for the base over the robot's own map, for moves that are not exploration steps.

The world drives the base along a polyline and stops at the first contact, so a straight line to a
stand beside furniture may cut through the furniture on the way. `Routes` answers, from where the
robot stands, which places it can reach and by which path, over the same distance field that
exploration plans on (free cells clear of obstacles by the robot's radius, paths kept off them:
`agent.planning.map_fields.drive_field`), and which places the map at least does not know to
be blocked (their floor perhaps never seen). Built from the map while the map holds still, it may
then be used from another thread while the tree ticks on. `step_towards` cuts a route to one
step's move, for goals that take several steps to reach.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from agent.mapping.occupancy import ExplorationMap
from agent.planning.frontier_plan import ExploreConfig, MovePlan
from agent.planning.map_fields import MapFields
from agent.planning.paths import DistanceField, simplify_path, truncate_path

#: Room kept, beyond the robot's radius, between a place to stand and the nearest obstacle on the
#: map: clearances are measured between 10 cm cells, so a thing may stand nearer than they say.
STAND_MARGIN_M = 0.1


@dataclass(frozen=True)
class Routes:
    """Every path from one start (world x, y): whether it `reaches` a place, the waypoints `to` it.
    ``clearance``: metres from each cell to the nearest obstacle on the map (+inf far from all
    the map knows, where it exceeds every margin asked of it: `agent.planning.map_fields`)."""

    field: DistanceField
    start_xy: np.ndarray
    clearance: np.ndarray
    robot_radius: float

    def reaches(self, xy: np.ndarray) -> bool:
        """Whether the base can drive to ``xy`` over the map and stand there clear of obstacles.

        Args:
            xy: the point (world).

        Returns:
            Whether it can.
        """
        cell = self._cell(xy)
        return cell is not None and bool(np.isfinite(self.field.metres[cell])) and self._clear(cell)

    def standable(self) -> np.ndarray:
        """Every cell `reaches` holds for, as a boolean grid.

        Returns:
            The grid.
        """
        return np.isfinite(self.field.metres) & (self.clearance >= self.robot_radius + STAND_MARGIN_M)

    def unblocked(self, xy: np.ndarray) -> bool:
        """Whether the map knows of no obstacle in the way of the base standing at ``xy``.

        Args:
            xy: the point (world).

        Returns:
            Whether nothing blocks it.
        """
        cell = self._cell(xy)
        return cell is not None and self._clear(cell)

    def to(self, xy: np.ndarray) -> np.ndarray:
        """Waypoints (K, 2) from the start to exactly ``xy``; raises ValueError if it is out of reach.

        Args:
            xy: the goal (world).

        Returns:
            The waypoints, simplified.

        Raises:
            ValueError: the goal is out of reach.
        """
        goal = np.asarray(xy, dtype=float)[:2]
        if not self.reaches(goal):
            raise ValueError(f"({goal[0]:.2f}, {goal[1]:.2f}) cannot be reached on the map")
        cells = self.field.path_to(tuple(int(v) for v in self.field.spec.to_cell(goal)))
        inner = self.field.spec.to_world(cells[1:-1]) if len(cells) > 2 else np.zeros((0, 2))
        return simplify_path(np.vstack([self.start_xy, inner, goal]))

    def _cell(self, xy: np.ndarray) -> tuple[int, int] | None:
        cell = self.field.spec.to_cell(np.asarray(xy, dtype=float)[:2])
        return (int(cell[0]), int(cell[1])) if self.field.spec.inside(cell) else None

    def _clear(self, cell: tuple[int, int]) -> bool:
        return bool(self.clearance[cell] >= self.robot_radius + STAND_MARGIN_M)


def routes_from(world_map: ExplorationMap, start_xy: np.ndarray, config: ExploreConfig = ExploreConfig(),
                squeeze_m: float = 0.0, fields: MapFields | None = None) -> Routes:
    """The routes from ``start_xy`` over ``world_map`` as it is now.

    Args:
        world_map: the robot's map.
        start_xy: where the routes start (world x, y).
        config: how far paths keep off obstacles.
        squeeze_m: let routes pass gaps that look this much too narrow on the map
            (`ExplorationMap.traversable`); where the base may stand is not squeezed.
        fields: the map's fields shared with other planners this step (computed afresh without).

    Returns:
        The routes.
    """
    fields = MapFields() if fields is None else fields
    start = np.asarray(start_xy, dtype=float)[:2]
    clearance = fields.clearance(world_map)
    field, _ = fields.drive_field(world_map, (float(start[0]), float(start[1])), config, squeeze_m)
    return Routes(field, start, clearance, world_map.config.robot_radius)


def step_towards(routes: Routes, goal_xy: np.ndarray, yaw: float | None, max_step_m: float) -> tuple[MovePlan, bool]:
    """One step's move along the path to ``goal_xy``, cut to ``max_step_m``, and whether it ends
    there. Arriving, the robot turns to ``yaw``; cut short (or with no ``yaw``), it faces the way
    it was going. Raises ValueError when the goal is out of reach.

    Args:
        routes: the routes from where the robot stands.
        goal_xy: the goal (world).
        yaw: the heading to arrive with, or None.
        max_step_m: the longest step.

    Returns:
        The move, and whether it arrives.

    Raises:
        ValueError: the goal is out of reach.
    """
    full = routes.to(goal_xy)
    path = truncate_path(full, max_step_m)
    arrives = len(path) == len(full) and bool(np.allclose(path[-1], full[-1]))
    if arrives and yaw is not None:
        heading = yaw
    else:
        last = path[-1] - path[-2]
        heading = math.atan2(last[1], last[0])
    goal = tuple(int(v) for v in routes.field.spec.to_cell(np.asarray(goal_xy, dtype=float)[:2]))
    return MovePlan(path, heading, None, float(routes.field.metres[goal])), arrives
