"""Shortest paths on the traversable grid, cut to the length the robot may drive in one step."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skimage.graph import MCP_Geometric

from agent.mapping.grid import GridSpec
from agent.planning.window import Window


@dataclass(frozen=True)
class DistanceField:
    """Path costs in (weighted) metres from one start cell to every cell (inf where unreachable).

    ``metres`` covers the whole grid; the search behind it may have covered only a part of it,
    whose first cell is grid cell ``corner``."""

    spec: GridSpec
    start: tuple[int, int]
    metres: np.ndarray
    _mcp: MCP_Geometric
    corner: tuple[int, int] = (0, 0)

    def path_to(self, cell: tuple[int, int]) -> np.ndarray:
        """The cells (K, 2) from the start to ``cell``; raises ValueError if it is unreachable.

        Args:
            cell: the goal cell (row, col).

        Returns:
            The path's cells.

        Raises:
            ValueError: the cell is unreachable.
        """
        if not np.isfinite(self.metres[cell]):
            raise ValueError(f"cell {cell} is not reachable from {self.start}")
        corner = np.asarray(self.corner)
        return np.asarray(self._mcp.traceback(tuple(np.asarray(cell) - corner)), dtype=int) + corner


def distance_field(spec: GridSpec, traversable: np.ndarray, start: tuple[int, int],
                   cell_cost: np.ndarray | None = None, window: Window | None = None) -> DistanceField:
    """Dijkstra over 8-connected traversable cells (diagonals cost √2 cells).

    ``cell_cost`` (≥ 1) weighs cells, e.g. to keep paths off walls; the field is then in weighted
    metres, which equal true metres along paths that stay clear.

    With a ``window`` holding the start and every traversable cell, ``traversable`` and
    ``cell_cost`` are its crops (`Window.crop`) and the search covers the window alone; the field
    is the one over the whole grid, paths and their ties included. The search never enters an
    impassable cell, it skips a neighbour off the window as it skips an impassable one, and which
    of two equal costs it settles first depends on the order it met them in, never on where they
    lie.

    Args:
        spec: the grid.
        traversable: the cells the robot may cross (the window's, with a window).
        start: the robot's cell (row, col) on the grid.
        cell_cost: each cell's weight (1 everywhere when None), of ``traversable``'s shape.
        window: the part of the grid searched (the whole grid when None).

    Returns:
        The field: metres from the start to every cell of the grid (inf where unreachable).

    Raises:
        ValueError: the start lies outside the window.
    """
    window = Window.whole(spec.shape) if window is None else window
    if not window.contains(start):
        raise ValueError(f"start cell {start} lies outside the window searched ({window})")
    local = (start[0] - window.top, start[1] - window.left)
    costs = np.where(traversable, 1.0 if cell_cost is None else cell_cost, np.inf)
    costs[local] = 1.0  # the robot stands there, whatever the map says
    mcp = MCP_Geometric(costs, fully_connected=True)
    cumulative, _ = mcp.find_costs([local])
    metres = cumulative * spec.resolution
    if metres.shape != spec.shape:
        metres = window.paste(metres, np.inf)
    return DistanceField(spec, start, metres, mcp, window.corner)


def clearance_cost(clearance_m: np.ndarray, radius_m: float, comfort_m: float, obstacle_cost: float) -> np.ndarray:
    """A cost per cell (≥ 1) that keeps paths off obstacles where there is room.

    1 where a cell is more than ``radius_m + comfort_m`` from the nearest obstacle, rising linearly
    to ``1 + obstacle_cost`` at ``radius_m``: a path hugs a wall only when nothing wider leads on.

    Args:
        clearance_m: each cell's distance to the nearest obstacle.
        radius_m: the robot's radius.
        comfort_m: the margin beyond it where paths pay nothing.
        obstacle_cost: the extra cost at the radius.

    Returns:
        The costs.
    """
    margin = (clearance_m - radius_m) / comfort_m
    return 1.0 + obstacle_cost * np.clip(1.0 - margin, 0.0, 1.0)


def truncate_path(points_xy: np.ndarray, max_length_m: float) -> np.ndarray:
    """The prefix of a polyline whose length is at most ``max_length_m``, ending exactly there.

    Args:
        points_xy: the polyline (K, 2).
        max_length_m: the most length kept.

    Returns:
        The prefix.
    """
    if len(points_xy) < 2:
        return points_xy
    segments = np.diff(points_xy, axis=0)
    lengths = np.hypot(segments[:, 0], segments[:, 1])
    travelled = np.concatenate([[0.0], np.cumsum(lengths)])
    if travelled[-1] <= max_length_m:
        return points_xy
    last = int(np.searchsorted(travelled, max_length_m, side="right")) - 1
    fraction = (max_length_m - travelled[last]) / lengths[last]
    if fraction <= 0:  # the cut falls on a waypoint: end there, without a zero-length last segment
        return points_xy[: last + 1]
    end = points_xy[last] + fraction * segments[last]
    return np.vstack([points_xy[: last + 1], end])


def simplify_path(points_xy: np.ndarray, tolerance_m: float = 0.05) -> np.ndarray:
    """Drop waypoints that lie on a straight line with their neighbours (fewer, longer segments).

    Each kept segment runs from the last kept point as far as every point it replaces stays within
    ``tolerance_m`` of it, so a bend made of small turns is kept rather than cut across.

    Args:
        points_xy: the path (K, 2).
        tolerance_m: how far a dropped point may lie off the kept segment.

    Returns:
        The kept points, the first and last included.
    """
    if len(points_xy) < 3:
        return points_xy
    points_xy = np.asarray(points_xy, dtype=float)
    kept = [0]
    for end in range(2, len(points_xy)):
        if _max_offset(points_xy[kept[-1] : end + 1]) > tolerance_m:
            kept.append(end - 1)
    kept.append(len(points_xy) - 1)
    return points_xy[kept]


def _max_offset(points_xy: np.ndarray) -> float:
    """The largest distance of the inner points from the segment joining the first and last."""
    start, end = points_xy[0], points_xy[-1]
    direction = end - start
    squared = float(direction @ direction)
    inner = points_xy[1:-1] - start
    t = np.clip(inner @ direction / squared, 0.0, 1.0) if squared > 0 else np.zeros(len(inner))
    return float(np.hypot(*(inner - t[:, None] * direction).T).max())


def path_length(points_xy: np.ndarray) -> float:
    """The length of a polyline (K, 2) in metres; 0 for fewer than two points.

    Args:
        points_xy: the polyline.

    Returns:
        The length.
    """
    return float(np.hypot(*np.diff(points_xy, axis=0).T).sum()) if len(points_xy) > 1 else 0.0
