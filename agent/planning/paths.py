"""Shortest paths on the traversable grid, cut to the length the robot may drive in one step."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from skimage.graph import MCP_Geometric

from agent.mapping.grid import GridSpec


@dataclass(frozen=True)
class DistanceField:
    """Path lengths in metres from one start cell to every cell (inf where unreachable)."""

    spec: GridSpec
    start: tuple[int, int]
    metres: np.ndarray
    _mcp: MCP_Geometric

    def path_to(self, cell: tuple[int, int]) -> np.ndarray:
        """The cells (K, 2) from the start to ``cell``; raises ValueError if it is unreachable."""
        if not np.isfinite(self.metres[cell]):
            raise ValueError(f"cell {cell} is not reachable from {self.start}")
        return np.asarray(self._mcp.traceback(cell), dtype=int)


def distance_field(spec: GridSpec, traversable: np.ndarray, start: tuple[int, int]) -> DistanceField:
    """Dijkstra over 8-connected traversable cells (diagonals cost √2 cells)."""
    costs = np.where(traversable, 1.0, np.inf)
    costs[start] = 1.0  # the robot stands there, whatever the map says
    mcp = MCP_Geometric(costs, fully_connected=True)
    cumulative, _ = mcp.find_costs([start])
    return DistanceField(spec, start, cumulative * spec.resolution, mcp)


def truncate_path(points_xy: np.ndarray, max_length_m: float) -> np.ndarray:
    """The prefix of a polyline whose length is at most ``max_length_m``, ending exactly there."""
    if len(points_xy) < 2:
        return points_xy
    segments = np.diff(points_xy, axis=0)
    lengths = np.hypot(segments[:, 0], segments[:, 1])
    travelled = np.concatenate([[0.0], np.cumsum(lengths)])
    if travelled[-1] <= max_length_m:
        return points_xy
    last = int(np.searchsorted(travelled, max_length_m, side="right")) - 1
    fraction = (max_length_m - travelled[last]) / lengths[last]
    end = points_xy[last] + fraction * segments[last]
    return np.vstack([points_xy[: last + 1], end])


def simplify_path(points_xy: np.ndarray, tolerance_m: float = 0.05) -> np.ndarray:
    """Drop waypoints that lie on a straight line with their neighbours (fewer, longer segments)."""
    if len(points_xy) < 3:
        return points_xy
    kept = [points_xy[0]]
    for previous, point, following in zip(points_xy[:-2], points_xy[1:-1], points_xy[2:]):
        direction = following - previous
        norm = np.hypot(*direction)
        offset = abs(direction[0] * (point[1] - previous[1]) - direction[1] * (point[0] - previous[0]))
        if norm == 0 or offset / norm > tolerance_m:
            kept.append(point)
    kept.append(points_xy[-1])
    return np.asarray(kept)


def path_length(points_xy: np.ndarray) -> float:
    return float(np.hypot(*np.diff(points_xy, axis=0).T).sum()) if len(points_xy) > 1 else 0.0
