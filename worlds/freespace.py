"""Where a round robot can be in a home: a rasterised occupancy grid and exact clearances.

The generator uses this to reject homes where a room cannot be reached; the scenario uses it to
pick a start pose in open space. Obstacles are the footprints of walls, furniture and objects on
the floor; everything outside the outline counts as occupied, so the outdoors is never "free".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy import ndimage

from worlds.things import point_rect_distance

if TYPE_CHECKING:
    from worlds.home import HomeSpec

RESOLUTION = 0.05


@dataclass(frozen=True)
class FreeSpace:
    """Cells free for a disc of ``radius``, their connected components, and each cell's clearance."""

    origin: tuple[float, float]
    resolution: float
    clearance_m: np.ndarray  # (ny, nx) distance from the cell centre to the nearest occupied cell
    components: np.ndarray  # (ny, nx) component label of cells free for the disc, 0 elsewhere
    room_of_cell: np.ndarray  # (ny, nx) index into home.rooms, -1 outside every room

    def cell_centre(self, row: int, col: int) -> tuple[float, float]:
        """The world (x, y) of a cell's centre.

        Args:
            row: the cell's row.
            col: the cell's column.

        Returns:
            The centre.
        """
        return (self.origin[0] + (col + 0.5) * self.resolution, self.origin[1] + (row + 0.5) * self.resolution)

    def cell_at(self, x: float, y: float) -> tuple[int, int]:
        """(row, col) of the cell holding (x, y), clamped to the grid.

        Args:
            x: the point's x (m).
            y: the point's y (m).

        Returns:
            The cell.
        """
        rows, cols = self.components.shape
        col = int(np.clip((x - self.origin[0]) // self.resolution, 0, cols - 1))
        row = int(np.clip((y - self.origin[1]) // self.resolution, 0, rows - 1))
        return row, col

    def main_component(self) -> int:
        """The component touching the most rooms (ties: the larger one); 0 if nothing is free.

        Returns:
            The component's label.
        """
        best, best_key = 0, (0, 0)
        for label in range(1, int(self.components.max()) + 1):
            cells = self.components == label
            rooms = np.unique(self.room_of_cell[cells])
            key = (int((rooms >= 0).sum()), int(cells.sum()))
            if key > best_key:
                best, best_key = label, key
        return best


def free_space(home: HomeSpec, radius: float, resolution: float = RESOLUTION) -> FreeSpace:
    """Rasterise ``home`` and find where a disc of ``radius`` fits, conservatively by half a cell.

    Args:
        home: the home.
        radius: the disc's radius (the robot's).
        resolution: the cell size (m).

    Returns:
        The free space: its components and the room of each cell.
    """
    x0, y0, x1, y1 = home.bounds
    nx, ny = int(np.ceil((x1 - x0) / resolution)), int(np.ceil((y1 - y0) / resolution))
    xs = x0 + (np.arange(nx) + 0.5) * resolution
    ys = y0 + (np.arange(ny) + 0.5) * resolution
    occupied = np.zeros((ny, nx), dtype=bool)
    half = resolution / 2
    for rx0, ry0, rx1, ry1 in home.obstacles():
        cols = (xs >= rx0 - half) & (xs <= rx1 + half)
        rows = (ys >= ry0 - half) & (ys <= ry1 + half)
        occupied[np.ix_(rows, cols)] = True
    padded = np.pad(occupied, 1, constant_values=True)  # the outdoors is not free
    clearance = ndimage.distance_transform_edt(~padded)[1:-1, 1:-1] * resolution
    components, _ = ndimage.label(clearance > radius + half, structure=np.ones((3, 3), dtype=bool))
    room_of_cell = np.full((ny, nx), -1, dtype=np.int32)
    for index, room in enumerate(home.rooms):
        rx0, ry0, rx1, ry1 = room.rect
        room_of_cell[np.ix_((ys >= ry0) & (ys <= ry1), (xs >= rx0) & (xs <= rx1))] = index
    return FreeSpace((x0, y0), resolution, clearance, components, room_of_cell)


def reachable_rooms(home: HomeSpec, radius: float, resolution: float = RESOLUTION) -> set[str]:
    """Names of the rooms a disc of ``radius`` can reach from the best-connected free region.

    Args:
        home: the home.
        radius: the disc's radius (the robot's).
        resolution: the cell size (m).

    Returns:
        The rooms' names.
    """
    space = free_space(home, radius, resolution)
    main = space.main_component()
    if main == 0:
        return set()
    indices = np.unique(space.room_of_cell[space.components == main])
    return {home.rooms[i].name for i in indices if i >= 0}


def clearance(home: HomeSpec, x: float, y: float) -> float:
    """Exact distance from (x, y) to the nearest wall, furniture or floor object footprint.

    Args:
        home: the home.
        x: the point's x (m).
        y: the point's y (m).

    Returns:
        The distance (m).
    """
    return min(point_rect_distance(x, y, rect) for rect in home.obstacles())
