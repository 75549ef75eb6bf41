"""The occupancy map as the frontier-property network sees it: one coarse grid of three values.

The coverage simulator maps at 0.05 m (the paper's cells), the EQA tree at 0.1 m, and the network
is trained at one resolution of its own. Everything that feeds it goes through `encode_map`, so the
training data and the planner at run time see maps made the same way:

- a coarse cell is OCCUPIED when any of its fine cells is occupied (walls stay closed);
- else FREE when any of its fine cells is known free (a doorway one fine cell wide stays open);
- else UNKNOWN.

The values are the paper's (§IV-A): 0 unknown, 1 occupied, 2 free.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

UNKNOWN, OCCUPIED, FREE = 0, 1, 2


def coarsening_factor(resolution: float, model_resolution: float) -> int:
    """How many fine cells a side of one coarse cell holds; they must divide exactly.

    Args:
        resolution: the fine cell size (m).
        model_resolution: the coarse cell size (m).

    Returns:
        The factor.

    Raises:
        ValueError: a size that is not positive, or one that does not divide the other.
    """
    if not (np.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution must be a positive number of metres, got {resolution}")
    if not (np.isfinite(model_resolution) and model_resolution > 0):
        raise ValueError(f"model_resolution must be a positive number of metres, got {model_resolution}")
    factor = model_resolution / resolution
    if factor < 1 - 1e-6 or abs(factor - round(factor)) > 1e-6:
        raise ValueError(f"the map's {resolution:g} m cells do not tile the network's {model_resolution:g} m cells")
    return int(round(factor))


def encode_map(free: np.ndarray, occupied: np.ndarray, resolution: float, model_resolution: float) -> np.ndarray:
    """The (H', W') uint8 map of UNKNOWN / OCCUPIED / FREE at ``model_resolution``.

    ``free`` and ``occupied`` are the known free and known occupied cells (bool, same 2-D shape) at
    ``resolution``; a cell in both counts as occupied. A grid whose sides are not a multiple of the
    factor is padded with unknown cells at the far (last row, last column) edges, so fine cell
    (r, c) always lies in coarse cell (r // f, c // f).

    Args:
        free: the known free cells.
        occupied: the known occupied cells.
        resolution: their cell size (m).
        model_resolution: the coarse cell size (m).

    Returns:
        The encoded map.

    Raises:
        ValueError: masks that are not bool, not 2-D or of different shapes; sizes that do not divide.
    """
    free, occupied = np.asarray(free), np.asarray(occupied)
    if free.dtype != bool or occupied.dtype != bool:
        raise ValueError(f"free and occupied must be bool masks, got {free.dtype} and {occupied.dtype}")
    if free.ndim != 2 or free.shape != occupied.shape:
        raise ValueError(f"free {free.shape} and occupied {occupied.shape} must be 2-D masks of one shape")
    factor = coarsening_factor(resolution, model_resolution)
    rows, cols = -(-free.shape[0] // factor), -(-free.shape[1] // factor)
    pad = ((0, rows * factor - free.shape[0]), (0, cols * factor - free.shape[1]))
    blocks = (rows, factor, cols, factor)
    any_occupied = np.pad(occupied, pad).reshape(blocks).any(axis=(1, 3))
    any_free = np.pad(free, pad).reshape(blocks).any(axis=(1, 3))
    encoded = np.full((rows, cols), UNKNOWN, dtype=np.uint8)
    encoded[any_free] = FREE
    encoded[any_occupied] = OCCUPIED
    return encoded


def coarse_cells(cells: np.ndarray, factor: int) -> np.ndarray:
    """The distinct coarse cells (K', 2) holding fine cells (K, 2) (rows, cols), in row-major order.

    Args:
        cells: the fine cells.
        factor: the coarsening factor.

    Returns:
        The coarse cells.

    Raises:
        ValueError: a factor below 1.
    """
    cells = np.asarray(cells, dtype=int).reshape(-1, 2)
    if factor < 1:
        raise ValueError(f"factor must be at least 1, got {factor}")
    return np.unique(cells // factor, axis=0)


def frontier_pixel_mask(encoded: np.ndarray) -> np.ndarray:
    """The pixels of an encoded map that read as frontier: FREE, with an UNKNOWN 8-neighbour.

    A frontier's pixels are the coarse cells of its fine cells (`coarse_cells`) that this mask
    holds; the training data hold exactly those, so a planner should average the network's
    outputs over the same.

    Args:
        encoded: the encoded map.

    Returns:
        The mask.
    """
    unknown_near = ndimage.binary_dilation(encoded == UNKNOWN, structure=np.ones((3, 3), dtype=bool))
    return (encoded == FREE) & unknown_near
