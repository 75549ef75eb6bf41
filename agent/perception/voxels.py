"""Voxel keys: world points on a fixed grid, packed into one int64 each so sets are sorted arrays.

RoboEXP keeps its low-level memory as voxels rather than raw points because merging and forgetting
then become set operations (intersection for 3D IoU, deletion for stale voxels) whose cost does not
grow with the number of frames seen. Here a voxel is the integer triple floor(p / size); the three
integers are offset by 2^20 and packed 21 bits each, which covers ±10 km at 1 cm and keeps a set of
voxels a sorted, unique ``int64`` array that numpy intersects in O(n log n).
"""

from __future__ import annotations

import numpy as np

_BITS = 21
_OFFSET = 1 << (_BITS - 1)
_MASK = (1 << _BITS) - 1
#: The 27 integer offsets of a voxel's 3x3x3 neighbourhood (itself included).
NEIGHBOURS = np.stack(np.meshgrid(*([np.arange(-1, 2)] * 3), indexing="ij"), axis=-1).reshape(-1, 3)


def voxel_indices(points: np.ndarray, size: float) -> np.ndarray:
    """Integer voxel coordinates (N, 3) of world points (N, 3) on a grid of ``size`` metres.

    Args:
        points: the points.
        size: the voxel size (m).

    Returns:
        The indices.

    Raises:
        ValueError: the size is not positive.
    """
    if size <= 0:
        raise ValueError(f"voxel size: {size} must be positive")
    return np.floor(np.asarray(points, dtype=float).reshape(-1, 3) / size).astype(np.int64)


def pack(indices: np.ndarray) -> np.ndarray:
    """One int64 key per integer voxel (N, 3); coordinates must lie within ±2^20.

    Args:
        indices: the integer voxels.

    Returns:
        The keys (N,).

    Raises:
        ValueError: a coordinate lies outside ±2^20.
    """
    idx = np.asarray(indices, dtype=np.int64).reshape(-1, 3) + _OFFSET
    if idx.size and (idx.min() < 0 or idx.max() > _MASK):
        raise ValueError(f"voxel indices: outside ±{_OFFSET} voxels, too far from the origin to pack")
    return (idx[:, 0] << (2 * _BITS)) | (idx[:, 1] << _BITS) | idx[:, 2]


def unpack(keys: np.ndarray) -> np.ndarray:
    """The integer voxel coordinates (N, 3) of packed keys (N,).

    Args:
        keys: the keys.

    Returns:
        The coordinates.
    """
    keys = np.asarray(keys, dtype=np.int64)
    return np.stack([(keys >> (2 * _BITS)) & _MASK, (keys >> _BITS) & _MASK, keys & _MASK], axis=1) - _OFFSET


def keys_of(points: np.ndarray, size: float) -> tuple[np.ndarray, np.ndarray]:
    """Sorted unique keys of the voxels that hold ``points``, and how many points fell in each.

    Args:
        points: the points (N, 3).
        size: the voxel size (m).

    Returns:
        The keys and the counts.
    """
    keys, counts = np.unique(pack(voxel_indices(points, size)), return_counts=True)
    return keys, counts.astype(np.int32)


def centres(keys: np.ndarray, size: float) -> np.ndarray:
    """World centres (N, 3) of packed voxels.

    Args:
        keys: the keys.
        size: the voxel size (m).

    Returns:
        The centres.
    """
    return (unpack(keys) + 0.5) * size


def dilate(keys: np.ndarray) -> np.ndarray:
    """Sorted unique keys of every voxel within one step (26-neighbourhood) of ``keys``.

    Args:
        keys: the keys.

    Returns:
        The grown keys.
    """
    if len(keys) == 0:
        return np.asarray(keys, dtype=np.int64)
    grown = unpack(keys)[None, :, :] + NEIGHBOURS[:, None, :]
    return np.unique(pack(grown.reshape(-1, 3)))


def near_count(keys: np.ndarray, others: np.ndarray) -> int:
    """How many of ``keys`` have ``others`` (sorted) in their 26-neighbourhood, themselves included.

    Counting with a one-voxel tolerance makes two views of one surface agree even when depth noise
    or the grid puts the same patch of surface in neighbouring voxels.

    Args:
        keys: the voxels counted.
        others: the voxels they are compared with (sorted).

    Returns:
        The count.
    """
    if len(keys) == 0 or len(others) == 0:
        return 0
    grown = pack((unpack(keys)[None, :, :] + NEIGHBOURS[:, None, :]).reshape(-1, 3))
    hit = np.isin(grown, others, assume_unique=False).reshape(len(NEIGHBOURS), len(keys))
    return int(hit.any(axis=0).sum())


def union(keys_a: np.ndarray, hits_a: np.ndarray, keys_b: np.ndarray, hits_b: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """Union of two voxel sets, summing the hit counts of voxels in both.

    Args:
        keys_a: the first set's keys.
        hits_a: its hit counts.
        keys_b: the second set's keys.
        hits_b: its hit counts.

    Returns:
        The union's keys and hit counts.
    """
    keys, inverse = np.unique(np.concatenate([keys_a, keys_b]), return_inverse=True)
    hits = np.bincount(inverse, weights=np.concatenate([hits_a, hits_b]), minlength=len(keys))
    return keys, hits.astype(np.int32)
