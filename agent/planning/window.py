"""A rectangle of the map's grid, so that planners work on the part the robot knows.

The map's grid is laid for the largest home with the robot at either end (`OccupancyConfig.size_m`),
so most of it stays unknown in any one home. A computation whose every input cell lies in a
rectangle (the cells that are set, and those it reads around them) gives the same answer there
when run on that rectangle alone; `Window` finds such a rectangle and moves arrays in and out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Window:
    """Rows ``[top, bottom)`` and columns ``[left, right)`` of a grid of ``shape``."""

    top: int
    bottom: int
    left: int
    right: int
    shape: tuple[int, int]

    @classmethod
    def whole(cls, shape: tuple[int, int]) -> Window:
        """The whole grid.

        Args:
            shape: the grid's (rows, cols).

        Returns:
            The window.
        """
        return cls(0, int(shape[0]), 0, int(shape[1]), (int(shape[0]), int(shape[1])))

    @classmethod
    def cell(cls, cell: tuple[int, int], shape: tuple[int, int]) -> Window:
        """The window of one cell.

        Args:
            cell: the cell (row, col).
            shape: the grid's (rows, cols).

        Returns:
            The window.
        """
        row, col = int(cell[0]), int(cell[1])
        return cls(row, row + 1, col, col + 1, (int(shape[0]), int(shape[1])))

    @classmethod
    def bounding(cls, mask: np.ndarray, margin: int = 0) -> Window | None:
        """The smallest window holding every true cell of ``mask``, widened by ``margin`` cells on
        each side and cut to the grid; None when no cell is true.

        Args:
            mask: a boolean grid.
            margin: the cells added on each side.

        Returns:
            The window, or None.
        """
        rows = np.flatnonzero(mask.any(axis=1))
        if len(rows) == 0:
            return None
        cols = np.flatnonzero(mask.any(axis=0))
        box = cls(int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1, mask.shape)
        return box.widened(margin)

    def widened(self, margin: int) -> Window:
        """This window with ``margin`` cells more on each side, cut to the grid.

        Args:
            margin: the cells added on each side.

        Returns:
            The window.
        """
        rows, cols = self.shape
        return Window(max(self.top - margin, 0), min(self.bottom + margin, rows),
                      max(self.left - margin, 0), min(self.right + margin, cols), self.shape)

    def including(self, cell: tuple[int, int]) -> Window:
        """The smallest window holding this one and ``cell`` (a cell of the grid).

        Args:
            cell: the cell (row, col).

        Returns:
            The window.
        """
        row, col = int(cell[0]), int(cell[1])
        return Window(min(self.top, row), max(self.bottom, row + 1), min(self.left, col), max(self.right, col + 1),
                      self.shape)

    def contains(self, cell: tuple[int, int]) -> bool:
        """Whether ``cell`` (row, col) lies in the window.

        Args:
            cell: the cell.

        Returns:
            Whether it does.
        """
        return self.top <= cell[0] < self.bottom and self.left <= cell[1] < self.right

    @property
    def corner(self) -> tuple[int, int]:
        """The grid cell (row, col) of the window's first cell."""
        return self.top, self.left

    @property
    def slices(self) -> tuple[slice, slice]:
        """The window as an index into a grid."""
        return slice(self.top, self.bottom), slice(self.left, self.right)

    def crop(self, grid: np.ndarray) -> np.ndarray:
        """The window's part of a grid (a view: not to be written to).

        Args:
            grid: an array of the grid's shape.

        Returns:
            The part.
        """
        return grid[self.slices]

    def paste(self, part: np.ndarray, fill: float | bool) -> np.ndarray:
        """A grid holding ``part`` in the window and ``fill`` everywhere else.

        Args:
            part: an array of the window's shape.
            fill: the value outside the window.

        Returns:
            The grid.
        """
        grid = np.full(self.shape, fill, dtype=part.dtype)
        grid[self.slices] = part
        return grid
