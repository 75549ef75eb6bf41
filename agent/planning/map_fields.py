"""The fields planners derive from the robot's map, computed once per state of the map.

Choosing a frontier, heading for storage and planning the way to a stand each need the map's
clearance (metres from every cell to the nearest obstacle) and a distance field of path costs
from the robot over the cells it may drive. The map changes only when a frame is fused into it or
the base reports where it drove or bumped (`ExplorationMap.revision` counts those changes), so
`MapFields` keeps what it computed for the map's current revision and hands the same arrays to
every caller until the map changes. Callers only read what they are handed.

Neither covers the whole grid, which is laid for the largest home and stays mostly unknown. The
drive field searches the box of the cells the robot may cross and its own (`distance_field`).
Clearance is computed on the `known_window`: the cells the map knows anything about, widened by
``WINDOW_MARGIN_M``. It is exact there, every occupied cell lying inside, and reads +inf outside,
where the true distance exceeds the margin. Clearance is compared with thresholds well below the
margin (the robot's radius, less a squeeze, in `ExplorationMap.traversable`; that plus a tenth in
`agent.planning.route.Routes`) or weighs traversable cells alone (`clearance_cost`), which are
known cells, so no answer changes. With nothing occupied the whole grid's transform is kept: it
then measures from beyond the grid's corner, not to +inf.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy import ndimage

from agent.mapping.occupancy import ExplorationMap
from agent.planning.paths import DistanceField, clearance_cost, distance_field
from agent.planning.window import Window

if TYPE_CHECKING:
    from agent.planning.frontier_plan import ExploreConfig

#: How far beyond the cells the map knows clearance is computed: more than any clearance that
#: planners compare with.
WINDOW_MARGIN_M = 2.0


def known_window(world_map: ExplorationMap, margin_m: float = WINDOW_MARGIN_M) -> Window | None:
    """The cells the map knows anything about (explored, floor seen, occupied, stood on, driven,
    bumped into, hit at obstacle height), widened by ``margin_m``; None when it knows nothing.

    Args:
        world_map: the robot's map.
        margin_m: the margin on each side.

    Returns:
        The window, or None.
    """
    known = (world_map.explored | world_map.floor_seen | world_map.occupied | world_map.stood | world_map.driven
             | world_map.bumped | world_map.obstacle_hits)
    return Window.bounding(known, int(np.ceil(margin_m / world_map.spec.resolution)))


def window_clearance(world_map: ExplorationMap) -> np.ndarray:
    """``world_map.clearance()`` in its `known_window`, +inf outside it (the whole grid's when
    nothing is occupied).

    Args:
        world_map: the robot's map.

    Returns:
        Metres from each cell to the nearest occupied cell (+inf far from all the map knows).
    """
    window = known_window(world_map)
    if window is None or not world_map.occupied.any():
        return world_map.clearance()
    part = ndimage.distance_transform_edt(~window.crop(world_map.occupied)) * world_map.spec.resolution
    return window.paste(part, np.inf)


def drive_field(world_map: ExplorationMap, robot_xy: tuple[float, float], clearance_m: np.ndarray,
                config: ExploreConfig, squeeze_m: float = 0.0) -> tuple[DistanceField, np.ndarray]:
    """Path costs from the robot over the cells it may drive (kept off walls where there is room).

    The search covers the box of those cells and the robot's own (`distance_field`).

    Args:
        world_map: the robot's map.
        robot_xy: where the robot stands (world x, y).
        clearance_m: the map's clearance (`window_clearance`), which callers often need too.
        config: how far paths keep off obstacles and what coming nearer costs.
        squeeze_m: see `ExplorationMap.traversable`.

    Returns:
        The distance field and the cells it was computed over.
    """
    spec = world_map.spec
    start = tuple(int(v) for v in spec.to_cell(np.asarray(robot_xy)))
    traversable = world_map.traversable(robot_xy, clearance_m, squeeze_m)
    window = Window.whole(spec.shape)
    if window.contains(start):  # off the grid, `distance_field` refuses the start
        box = Window.bounding(traversable)
        window = Window.cell(start, spec.shape) if box is None else box.including(start)
    cell_cost = clearance_cost(window.crop(clearance_m), world_map.config.robot_radius, config.comfort_m,
                               config.obstacle_cost)
    return distance_field(spec, window.crop(traversable), start, cell_cost, window), traversable


class MapFields:
    """Clearance and drive fields of one map, kept until the map changes."""

    def __init__(self) -> None:
        self._map: ExplorationMap | None = None
        self._revision = -1
        self._clearance: np.ndarray | None = None
        self._fields: dict[tuple[float, float, float, float, float], tuple[DistanceField, np.ndarray]] = {}

    def clearance(self, world_map: ExplorationMap) -> np.ndarray:
        """`window_clearance` of the map as it stands now, computed once per revision.

        Args:
            world_map: the robot's map.

        Returns:
            Metres from each cell to the nearest occupied cell, +inf far from all the map knows
            (not to be written to).
        """
        self._follow(world_map)
        if self._clearance is None:
            self._clearance = window_clearance(world_map)
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
        clearance_m = self.clearance(world_map)
        if key not in self._fields:
            self._fields[key] = drive_field(world_map, xy, clearance_m, config, squeeze_m)
        return self._fields[key]

    def _follow(self, world_map: ExplorationMap) -> None:
        """Forget what was computed for another map or an earlier revision of this one."""
        if world_map is not self._map or world_map.revision != self._revision:
            self._map, self._revision = world_map, world_map.revision
            self._clearance = None
            self._fields = {}
