"""Frontiers: free cells on the boundary between explored and unexplored space.

Plain frontier-based exploration (FBE) drives to the nearest frontier cluster. The cluster's
normal points into the unexplored side, which is where the robot should look when it arrives.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from agent.mapping.grid import GridSpec
from agent.planning.window import Window

_EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True)
class Frontier:
    """One frontier cluster: its cells, a representative cell, and the unit normal (x, y)."""

    cells: np.ndarray  # (K, 2) rows, cols
    centre: tuple[int, int]  # the cluster cell nearest the cluster's mean
    normal: np.ndarray  # unit (x, y) into unexplored space

    @property
    def size(self) -> int:
        return len(self.cells)


def frontier_cells(reachable: np.ndarray, explored: np.ndarray, occupied: np.ndarray,
                   min_unexplored_neighbours: int = 2) -> np.ndarray:
    """Reachable cells with at least that many 8-neighbours that are unexplored and not occupied.

    Only the reachable cells' window and its ring of neighbours is read (`Window.bounding`).

    Args:
        reachable: the cells the robot can reach.
        explored: the cells seen.
        occupied: the cells seen occupied.
        min_unexplored_neighbours: the fewest open unknown neighbours a frontier cell has.

    Returns:
        A boolean grid of the frontier cells.
    """
    window = Window.bounding(reachable, margin=1)
    if window is None:
        return np.zeros(reachable.shape, dtype=bool)
    open_unknown = (~window.crop(explored) & ~window.crop(occupied)).astype(np.int32)
    counts = ndimage.convolve(open_unknown, _EIGHT.astype(np.int32), mode="constant", cval=0) - open_unknown
    return window.paste(window.crop(reachable) & (counts >= min_unexplored_neighbours), False)


def cluster_frontiers(spec: GridSpec, cells_mask: np.ndarray, explored: np.ndarray, occupied: np.ndarray,
                      min_size: int = 3) -> list[Frontier]:
    """Group frontier cells into 8-connected clusters of at least ``min_size`` cells.

    Clusters come in the order of their first cell row by row, each with its cells in that order.
    Only the frontier cells' window and its ring of neighbours is read (`Window.bounding`).

    Args:
        spec: the grid.
        cells_mask: the frontier cells (`frontier_cells`).
        explored: the cells seen.
        occupied: the cells seen occupied.
        min_size: the fewest cells a frontier has.

    Returns:
        The frontiers, each with its centre cell and its normal towards the unknown.
    """
    window = Window.bounding(cells_mask, margin=1)
    if window is None:
        return []
    labels, count = ndimage.label(window.crop(cells_mask), structure=_EIGHT)
    open_unknown = ~window.crop(explored) & ~window.crop(occupied)
    local = np.argwhere(labels)  # row by row; a stable sort by label keeps that order in each cluster
    local = local[np.argsort(labels[local[:, 0], local[:, 1]], kind="stable")]
    ends = np.cumsum(np.bincount(labels[local[:, 0], local[:, 1]], minlength=count + 1)[1:])
    frontiers = []
    for part in np.split(local, ends[:-1]):
        if len(part) < min_size:
            continue
        cells = part + np.asarray(window.corner)
        mean = cells.mean(axis=0)
        centre = tuple(int(v) for v in cells[np.argmin(np.hypot(*(cells - mean).T))])
        frontiers.append(Frontier(cells, centre, _normal(part, open_unknown)))
    return frontiers


def _normal(cells: np.ndarray, open_unknown: np.ndarray) -> np.ndarray:
    """Mean direction from the cluster's cells to their unexplored neighbours, as unit (x, y)."""
    rows, cols = open_unknown.shape
    total = np.zeros(2)
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr == dc == 0:
                continue
            r, c = cells[:, 0] + dr, cells[:, 1] + dc
            ok = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
            hits = np.count_nonzero(open_unknown[r[ok], c[ok]])
            total += hits * np.array([dc, dr]) / np.hypot(dc, dr)
    norm = np.hypot(*total)
    return total / norm if norm > 0 else np.array([1.0, 0.0])
