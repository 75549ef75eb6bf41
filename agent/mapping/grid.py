"""A 2D grid laid over the floor: cell indices <-> world coordinates.

Arrays are indexed ``[row, col]`` with rows along +y and columns along +x, so ``grid[iy, ix]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class GridSpec:
    """Where a grid lies: the world (x, y) of cell (0, 0)'s lower-left corner, the cell size, the shape."""

    origin_xy: tuple[float, float]
    resolution: float
    shape: tuple[int, int]  # (rows, cols)

    @classmethod
    def centred(cls, centre_xy: tuple[float, float], size_m: float, resolution: float) -> GridSpec:
        """A square grid of at least ``size_m`` a side centred on a point.

        Args:
            centre_xy: the centre (world, m).
            size_m: the side (rounded up to whole cells).
            resolution: the cell size (m).

        Returns:
            The grid.
        """
        cells = int(np.ceil(size_m / resolution))
        half = cells * resolution / 2
        return cls((centre_xy[0] - half, centre_xy[1] - half), resolution, (cells, cells))

    def to_cell(self, xy: np.ndarray) -> np.ndarray:
        """World (..., 2) points -> integer (..., 2) cells as (row, col); may fall outside the grid.

        Args:
            xy: the world points.

        Returns:
            The cells.
        """
        xy = np.asarray(xy, dtype=float)
        col = np.floor((xy[..., 0] - self.origin_xy[0]) / self.resolution)
        row = np.floor((xy[..., 1] - self.origin_xy[1]) / self.resolution)
        return np.stack([row, col], axis=-1).astype(int)

    def to_world(self, cells: np.ndarray) -> np.ndarray:
        """Integer (..., 2) cells as (row, col) -> world (..., 2) cell centres as (x, y).

        Args:
            cells: the cells.

        Returns:
            The cell centres.
        """
        cells = np.asarray(cells, dtype=float)
        x = self.origin_xy[0] + (cells[..., 1] + 0.5) * self.resolution
        y = self.origin_xy[1] + (cells[..., 0] + 0.5) * self.resolution
        return np.stack([x, y], axis=-1)

    def inside(self, cells: np.ndarray) -> np.ndarray:
        """Which cells (..., 2) lie within the grid.

        Args:
            cells: the cells as (row, col).

        Returns:
            A boolean (...) array.
        """
        cells = np.asarray(cells)
        return (
            (cells[..., 0] >= 0)
            & (cells[..., 0] < self.shape[0])
            & (cells[..., 1] >= 0)
            & (cells[..., 1] < self.shape[1])
        )

    def disc(self, centre_xy: tuple[float, float], radius_m: float) -> np.ndarray:
        """A boolean grid that is true on cells whose centre lies within ``radius_m`` of the point.

        Args:
            centre_xy: the disc's centre (world, m).
            radius_m: its radius.

        Returns:
            The grid's boolean mask.
        """
        mask = np.zeros(self.shape, dtype=bool)
        window = self.disc_window(centre_xy, radius_m)
        if window is not None:
            mask[window[0]] = window[1]
        return mask

    def disc_window(self, centre_xy: tuple[float, float],
                    radius_m: float) -> tuple[tuple[slice, slice], np.ndarray] | None:
        """`disc` as the window of the grid around the disc and the disc's mask over that window:
        what to use where the disc is marked into a grid every step, the map being large.

        Args:
            centre_xy: the disc's centre (world, m).
            radius_m: its radius.

        Returns:
            (rows, cols) slices and the mask over them; None when the disc misses the grid.
        """
        return self.discs_window(np.asarray(centre_xy, dtype=float).reshape(1, 2), radius_m)

    def discs_window(self, centres_xy: np.ndarray,
                     radius_m: float) -> tuple[tuple[slice, slice], np.ndarray] | None:
        """The union of discs of one radius (a swept path, say) over the window around them.

        Args:
            centres_xy: the discs' centres (N, 2) (world, m).
            radius_m: their radius.

        Returns:
            (rows, cols) slices and the mask over them; None when the discs miss the grid.
        """
        centres_xy = np.asarray(centres_xy, dtype=float).reshape(-1, 2)
        low = np.maximum(self.to_cell(centres_xy - radius_m).min(axis=0), 0)
        high = np.minimum(self.to_cell(centres_xy + radius_m).max(axis=0) + 1, self.shape)
        if np.any(low >= high):
            return None
        rows, cols = np.mgrid[low[0]:high[0], low[1]:high[1]]
        cells = self.to_world(np.stack([rows, cols], axis=-1))[..., None, :]
        inside = np.hypot(cells[..., 0] - centres_xy[:, 0], cells[..., 1] - centres_xy[:, 1]) <= radius_m
        return (slice(low[0], high[0]), slice(low[1], high[1])), inside.any(axis=-1)

    def extent(self) -> tuple[float, float, float, float]:
        """(xmin, xmax, ymin, ymax), for plotting.

        Returns:
            The extent.
        """
        x0, y0 = self.origin_xy
        return (x0, x0 + self.shape[1] * self.resolution, y0, y0 + self.shape[0] * self.resolution)
