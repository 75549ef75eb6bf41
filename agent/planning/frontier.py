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
    local = np.argwhere(labels)  # row by row; a stable sort by label keeps that order in each cluster
    cluster = labels[local[:, 0], local[:, 1]]
    order = np.argsort(cluster, kind="stable")
    local, cluster = local[order], cluster[order]
    totals = _normal_sums(local, cluster, count, ~window.crop(explored) & ~window.crop(occupied))
    norms = np.hypot(totals[:, 0], totals[:, 1])
    ends = np.cumsum(np.bincount(cluster, minlength=count + 1)[1:])
    frontiers = []
    for index, part in enumerate(np.split(local, ends[:-1])):
        if len(part) < min_size:
            continue
        cells = part + np.asarray(window.corner)
        mean = cells.mean(axis=0)
        centre = tuple(int(v) for v in cells[np.argmin(np.hypot(*(cells - mean).T))])
        normal = totals[index] / norms[index] if norms[index] > 0 else np.array([1.0, 0.0])
        frontiers.append(Frontier(cells, centre, normal))
    return frontiers


def _normal_sums(cells: np.ndarray, cluster: np.ndarray, count: int, open_unknown: np.ndarray) -> np.ndarray:
    """Per cluster (count, 2), the sum over its cells of the unit (x, y) steps to their neighbours
    that are open unknown: the direction of its normal. ``cells`` (K, 2) lie in ``open_unknown``'s
    window, whose ring of neighbours holds theirs unless the grid ends there; ``cluster`` (K,) are
    their labels, 1 to ``count``."""
    padded = np.pad(open_unknown, 1)  # nothing beyond the grid is open unknown
    totals = np.zeros((count, 2))
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            if dr == dc == 0:
                continue
            hit = padded[cells[:, 0] + 1 + dr, cells[:, 1] + 1 + dc]
            hits = np.bincount(cluster[hit], minlength=count + 1)[1:]
            totals += hits[:, None] * np.array([dc, dr]) / np.hypot(dc, dr)
    return totals
