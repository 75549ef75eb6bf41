"""The training data's files: one compressed archive per home, its arrays checked on the way in.

A shard (``home-SSSSS.npz``) holds one home's snapshots (`agent.lfe.samples` makes them, the trainer
reads them):

- ``maps``: uint8 (S, H, W), each snapshot's map encoded by `agent.lfe.raster.encode_map`;
- ``pixels``: int32 (P, 3), (snapshot, row, col) of every frontier pixel, grouped by snapshot;
- ``targets``: float32 (P, 3), R_A (m²), D_in and D_out (m) of the frontier each pixel belongs to;
- ``resolution``: float64, the maps' cell size in metres; ``seed``: int64, the home's seed.

Shards are read with ``allow_pickle=False``: an archive never runs code.
"""

from __future__ import annotations

import math
import os
import zipfile
from pathlib import Path

import numpy as np

SHARD_ARRAYS = {"maps": (np.uint8, 3), "pixels": (np.int32, 2), "targets": (np.float32, 2),
                "resolution": (np.float64, 0), "seed": (np.int64, 0)}
"""Each array of a shard: its dtype and number of dimensions."""


SHARD_GLOB = "home-*.npz"


def shard_path(out_dir: Path, seed: int) -> Path:
    """Where the shard of the home made with ``seed`` is written in ``out_dir``.

    Args:
        out_dir: the data directory.
        seed: the home's seed.

    Returns:
        The path.
    """
    return Path(out_dir) / f"home-{seed:05d}.npz"


def shard_paths(data_dir: Path) -> list[Path]:
    """The shards of a data directory, sorted by name; an error if there are none.

    Args:
        data_dir: the data directory.

    Returns:
        The paths.

    Raises:
        FileNotFoundError: no shard there.
    """
    paths = sorted(Path(data_dir).glob(SHARD_GLOB))
    if not paths:
        raise FileNotFoundError(f"{data_dir}: no training shards ({SHARD_GLOB})")
    return paths


def write_shard(path: Path, arrays: dict[str, np.ndarray]) -> None:
    """Write a shard under a temporary name and rename it into place, so it appears whole or not at all.

    Args:
        path: the shard.
        arrays: its arrays.
    """
    partial = path.with_name(path.name + ".part")
    with open(partial, "wb") as handle:
        np.savez_compressed(handle, **arrays)
    os.replace(partial, path)


def load_shard(path: Path) -> dict[str, np.ndarray]:
    """Read one shard and check it: a ValueError naming the file and the field when it is malformed.

    Args:
        path: the shard.

    Returns:
        Its arrays by name.

    Raises:
        ValueError: the file is unreadable or a field is malformed.
    """
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as archive:
            arrays = {name: archive[name] for name in archive.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as error:
        raise ValueError(f"{path}: not a readable shard: {error}") from None
    try:
        _check_shard(arrays)
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None
    return arrays


def _check_shard(arrays: dict[str, np.ndarray]) -> None:
    """Raise a ValueError naming the first field of a shard that is missing or malformed."""
    missing = sorted(set(SHARD_ARRAYS) - set(arrays))
    if missing:
        raise ValueError(f"{missing[0]}: missing (a shard holds {', '.join(SHARD_ARRAYS)})")
    for name, (dtype, ndim) in SHARD_ARRAYS.items():
        array = arrays[name]
        if array.dtype != dtype or array.ndim != ndim:
            raise ValueError(f"{name}: must be {np.dtype(dtype).name} with {ndim} dimensions, "
                             f"got {array.dtype} with shape {array.shape}")
    maps, pixels, targets = arrays["maps"], arrays["pixels"], arrays["targets"]
    if not set(np.unique(maps).tolist()) <= {0, 1, 2}:
        raise ValueError("maps: values must be 0 (unknown), 1 (occupied) or 2 (free)")
    if pixels.shape[1] != 3:
        raise ValueError(f"pixels: must be (P, 3) (snapshot, row, col), got shape {pixels.shape}")
    if targets.shape != (len(pixels), 3):
        raise ValueError(f"targets: must be ({len(pixels)}, 3) like pixels, got shape {targets.shape}")
    if len(pixels) and ((pixels < 0).any() or (pixels >= np.array(maps.shape)).any()):
        raise ValueError(f"pixels: index outside maps {maps.shape}")
    if len(pixels) and (np.diff(pixels[:, 0]) < 0).any():
        raise ValueError("pixels: must be grouped by snapshot, in order")
    if not np.isfinite(targets).all() or (targets < 0).any():
        raise ValueError("targets: must be finite and non-negative")
    resolution = float(arrays["resolution"])
    if not (math.isfinite(resolution) and resolution > 0):
        raise ValueError(f"resolution: must be a positive number of metres, got {resolution}")
