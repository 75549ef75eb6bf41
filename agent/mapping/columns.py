"""Which floor cells hold a floor surface and which an obstacle surface, renewed where a frame
changed the TSDF.

A cell's column holds floor when a surface voxel (`agent.mapping.surface`) above it lies in the
floor band, and an obstacle when one lies between the obstacle heights. Reading every voxel out
of the volume each step costs time that grows with the home and the episode; a frame changes only
the blocks its depth reached (`TsdfMap.integrate` says which), and whether a voxel holds a surface
depends on it and its six neighbours alone. So after a frame only the cells over the touched
block columns, widened by one voxel, can change; they are recomputed from the blocks in the
columns around them, and every other cell keeps its value. Renewing with every allocated block
touched is the whole projection from scratch, and the two agree bit for bit
(tests/test_mapping_columns.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from agent.mapping.grid import GridSpec
from agent.mapping.surface import surface_mask
from agent.mapping.tsdf import TsdfMap

_EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True)
class ColumnBands:
    """Heights (m) that make a surface floor or obstacle, and the surface test's thresholds."""

    floor: tuple[float, float]
    obstacle: tuple[float, float]
    max_pair_tsdf: float
    near_tsdf: float


class SurfaceColumns:
    """The 2D ``floor`` and ``obstacle`` grids of a TSDF, kept up to date frame by frame.

    ``spec`` must be a lattice grid (`agent.mapping.occupancy.lattice_grid`) whose cell is a whole
    number of voxels: cells are found from voxel indices, which then lie a quarter cell or more
    from every cell boundary.

    Args:
        spec: the grid.
        tsdf: the TSDF the columns are read from.
        bands: the heights and surface thresholds.
    """

    def __init__(self, spec: GridSpec, tsdf: TsdfMap, bands: ColumnBands) -> None:
        self.spec = spec
        self.tsdf = tsdf
        self.bands = bands
        self.floor = np.zeros(spec.shape, dtype=bool)
        self.obstacle = np.zeros(spec.shape, dtype=bool)
        size, resolution = tsdf.config.voxel_size, tsdf.config.block_resolution
        voxels_per_cell = int(round(spec.resolution / size))
        # blocks beside a touched column whose voxels a recomputed cell needs, with their neighbours
        self._ring = math.ceil((voxels_per_cell + 1) / resolution)
        lowest = math.floor(min(bands.floor[0], bands.obstacle[0]) / size) - 1
        highest = math.ceil(max(bands.floor[1], bands.obstacle[1]) / size) + 1
        self._block_z = (lowest // resolution, highest // resolution)

    def renew(self, touched: np.ndarray) -> None:
        """Recompute the cells over the touched blocks after a frame was fused.

        Args:
            touched: integer block coordinates (M, 3) the frame updated (`TsdfMap.integrate`).
        """
        if len(touched) == 0:
            return
        resolution = self.tsdf.config.block_resolution
        columns = np.unique(np.asarray(touched, dtype=np.int64)[:, :2], axis=0)
        low = columns.min(axis=0) - self._ring
        high = columns.max(axis=0) + self._ring
        raster = np.zeros(tuple(high - low + 1), dtype=bool)  # touched block columns, [bx, by]
        raster[tuple((columns - low).T)] = True
        gathered = self._blocks_around(raster, low)
        if len(gathered) == 0:
            return
        field, origin = self._dense(gathered)
        surface = surface_mask(field, self.bands.max_pair_tsdf, self.bands.near_tsdf)
        heights = (origin[2] + np.arange(field.shape[2])) * self.tsdf.config.voxel_size
        floor = surface[:, :, (heights >= self.bands.floor[0]) & (heights <= self.bands.floor[1])].any(axis=2)
        obstacle = surface[:, :, (heights >= self.bands.obstacle[0]) & (heights <= self.bands.obstacle[1])].any(axis=2)
        # voxel columns over a touched block or one voxel beside one: those whose answer may change
        offset = (origin[:2] // resolution) - low
        touched_voxels = np.kron(raster, np.ones((resolution, resolution), dtype=bool))
        touched_voxels = ndimage.binary_dilation(touched_voxels, structure=_EIGHT)
        touched_voxels = touched_voxels[offset[0] * resolution:, offset[1] * resolution:][:field.shape[0], :field.shape[1]]
        self._write(origin, touched_voxels, floor, obstacle)

    def _blocks_around(self, raster: np.ndarray, low: np.ndarray) -> np.ndarray:
        """Allocated blocks at the heights that matter in the touched block columns and the ring
        around them."""
        near = ndimage.binary_dilation(raster, structure=np.ones((2 * self._ring + 1,) * 2, dtype=bool))
        blocks = self.tsdf.blocks()
        local = blocks[:, :2] - low
        inside = np.all((local >= 0) & (local < raster.shape), axis=1)
        inside &= (blocks[:, 2] >= self._block_z[0]) & (blocks[:, 2] <= self._block_z[1])
        inside[inside] = near[local[inside, 0], local[inside, 1]]
        return blocks[inside]

    def _dense(self, blocks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The blocks' TSDF laid into one dense array (NaN where unobserved) and the voxel index
        of its first element."""
        resolution = self.tsdf.config.block_resolution
        low = blocks.min(axis=0)
        counts = blocks.max(axis=0) - low + 1
        dense = np.full((*counts, resolution, resolution, resolution), np.nan, dtype=np.float32)
        dense[tuple((blocks - low).T)] = self.tsdf.fields(blocks)
        field = dense.transpose(0, 3, 1, 4, 2, 5).reshape(tuple(counts * resolution))
        return field, low * resolution

    def _write(self, origin: np.ndarray, renew: np.ndarray, floor: np.ndarray, obstacle: np.ndarray) -> None:
        """Set the cells the ``renew`` voxel columns fall in from the columns' floor and obstacle
        flags (all [x, y] from voxel ``origin``)."""
        size = self.tsdf.config.voxel_size
        x = (origin[0] + np.arange(renew.shape[0])) * size
        y = (origin[1] + np.arange(renew.shape[1])) * size
        cols = np.floor((x - self.spec.origin_xy[0]) / self.spec.resolution).astype(int)
        rows = np.floor((y - self.spec.origin_xy[1]) / self.spec.resolution).astype(int)
        col_in = (cols >= 0) & (cols < self.spec.shape[1])
        row_in = (rows >= 0) & (rows < self.spec.shape[0])
        renew = renew & col_in[:, None] & row_in[None, :]
        at = np.nonzero(renew)
        cell_rows, cell_cols = rows[at[1]], cols[at[0]]
        cells = np.zeros(self.spec.shape, dtype=bool)
        cells[cell_rows, cell_cols] = True
        self.floor[cells] = False
        self.obstacle[cells] = False
        # every voxel column of a renewed cell is in the dense block, so each cell's flags are whole
        rows_in, cols_in = np.clip(rows, 0, self.spec.shape[0] - 1), np.clip(cols, 0, self.spec.shape[1] - 1)
        within = col_in[:, None] & row_in[None, :] & cells[rows_in[None, :], cols_in[:, None]]
        for flags, grid in ((floor, self.floor), (obstacle, self.obstacle)):
            hit = np.nonzero(flags & within)
            grid[rows[hit[1]], cols[hit[0]]] = True
