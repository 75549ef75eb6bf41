"""The frontier-property UNet's training set: shards read at the network's resolution, split by home,
and sampled as crops around frontier pixels.

Each step of training (`agent.lfe.train`) sees a batch of crops of the map (``crop`` pixels a
side, 12.8 m at 0.1 m cells) centred near a random frontier pixel, turned and mirrored at random
(the properties do not change when the house does). Homes, not snapshots, are held out for
validation: snapshots of one home share its layout, and a network validated on the home it
trained on would look better than it is.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

from agent.lfe import shards
from agent.lfe.model import TARGETS, encode_input, map_window, to_network


@dataclass(frozen=True)
class Shard:
    """One home's snapshots, with the frontier pixels of snapshot ``s`` at rows ``starts[s]:starts[s+1]``.

    Args:
        name: the shard file's stem (``home-SSSSS``).
        maps: uint8 (S, H, W) encoded maps.
        pixels: int (P, 2) row, col of the frontier pixels, grouped by snapshot.
        targets: float32 (P, 3) R_A, D_in, D_out of each pixel, in natural units.
        starts: (S + 1,) offsets into ``pixels`` per snapshot.
    """

    name: str
    maps: np.ndarray
    pixels: np.ndarray
    targets: np.ndarray
    starts: np.ndarray

    def frontier_pixels(self, snapshot: int) -> tuple[np.ndarray, np.ndarray]:
        """The frontier pixels of one snapshot and their targets.

        Args:
            snapshot: the snapshot's index.

        Returns:
            Pixels (K, 2) and targets (K, 3).
        """
        rows = slice(self.starts[snapshot], self.starts[snapshot + 1])
        return self.pixels[rows], self.targets[rows]


def load_shard(path: Path, model_resolution: float) -> Shard:
    """Read and check one home's shard (`agent.lfe.shards.load_shard`) at the network's resolution.

    Args:
        path: the shard file.
        model_resolution: the network's cells (m); the shard's maps must be at it.

    Returns:
        The home's snapshots with their frontier pixels grouped by snapshot.

    Raises:
        ValueError: a malformed shard, or maps at another resolution.
    """
    arrays = shards.load_shard(path)
    resolution = float(arrays["resolution"])
    if not math.isclose(resolution, model_resolution):
        raise ValueError(f"{path}: maps are at {resolution:g} m, the network reads {model_resolution:g} m")
    pixels = arrays["pixels"]
    starts = np.searchsorted(pixels[:, 0], np.arange(len(arrays["maps"]) + 1))
    return Shard(Path(path).stem, arrays["maps"], pixels[:, 1:].astype(np.int64), arrays["targets"], starts)


def split_homes(paths: Sequence[Path], val_fraction: float, seed: int) -> tuple[list[Path], list[Path]]:
    """Hold whole homes out for validation, at least one on each side.

    Each home draws a number from a generator seeded by (seed, its name) and the lowest go to
    validation, so the split depends on the seed and the names only, and adding homes moves few
    of the old ones across.

    Args:
        paths: the shards.
        val_fraction: the share of homes to hold out (rounded, at least one, never all).
        seed: the split's seed.

    Returns:
        The training shards and the validation shards, each in the order of ``paths``.

    Raises:
        ValueError: fewer than two shards.
    """
    if len(paths) < 2:
        raise ValueError(f"need at least two homes to hold one out for validation, got {len(paths)}")
    draws = [np.random.default_rng([seed, zlib.crc32(Path(p).stem.encode())]).random() for p in paths]
    count = min(max(round(val_fraction * len(paths)), 1), len(paths) - 1)
    held_out = set(np.argsort(draws, kind="stable")[:count].tolist())
    return ([p for i, p in enumerate(paths) if i not in held_out],
            [p for i, p in enumerate(paths) if i in held_out])


@dataclass(frozen=True)
class Batch:
    """A batch of crops as the network and the loss read them.

    Args:
        inputs: network inputs (B, 4, C, C).
        targets: targets in network units (B, 3, C, C).
        mask: the frontier pixels (B, C, C).
    """

    inputs: torch.Tensor
    targets: torch.Tensor
    mask: torch.Tensor

    def to(self, device: torch.device) -> Batch:
        """The same batch on ``device``.

        Args:
            device: where the network runs.

        Returns:
            A batch whose tensors are on ``device``.
        """
        return Batch(self.inputs.to(device), self.targets.to(device), self.mask.to(device))


class CropSampler:
    """Crops of snapshots centred near a frontier pixel, padded with unknown beyond the map.

    Snapshots are drawn uniformly (each with at least one frontier pixel), then one of their
    frontier pixels, then an offset of up to a quarter crop so the frontier is not always centred.

    Args:
        shards: the homes to crop.
        crop: the side of a crop in pixels.

    Raises:
        ValueError: no snapshot of ``shards`` has a frontier pixel.
    """

    def __init__(self, shards: Sequence[Shard], crop: int) -> None:
        self.shards = list(shards)
        self.crop = crop
        self.snapshots = [(h, s) for h, shard in enumerate(self.shards)
                          for s in range(len(shard.maps)) if shard.starts[s + 1] > shard.starts[s]]
        if not self.snapshots:
            raise ValueError(f"no frontier pixels in homes {', '.join(s.name for s in self.shards)}")

    def batch(self, rng: np.random.Generator, size: int, augment: bool) -> Batch:
        """Draw a batch of crops.

        Args:
            rng: draws the snapshots, pixels, offsets and turns.
            size: crops in the batch.
            augment: turn and mirror each crop at random.

        Returns:
            The crops, ready for the network.
        """
        maps, masks, targets = zip(*(self._sample(rng, augment) for _ in range(size)))
        mask = torch.from_numpy(np.stack(masks))
        return Batch(encode_input(np.stack(maps), mask), to_network(np.stack(targets)), mask)

    def _sample(self, rng: np.random.Generator, augment: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        home, snapshot = self.snapshots[rng.integers(len(self.snapshots))]
        shard = self.shards[home]
        pixels, values = shard.frontier_pixels(snapshot)
        centre = pixels[rng.integers(len(pixels))] + rng.integers(-(self.crop // 4), self.crop // 4 + 1, size=2)
        corner = centre - self.crop // 2
        map_crop = map_window(shard.maps[snapshot], corner, (self.crop, self.crop))
        inside = ((pixels >= corner) & (pixels < corner + self.crop)).all(axis=1)
        rows, cols = (pixels[inside] - corner).T
        mask = np.zeros((self.crop, self.crop), dtype=bool)
        mask[rows, cols] = True
        target = np.zeros((len(TARGETS), self.crop, self.crop), dtype=np.float32)
        target[:, rows, cols] = values[inside].T
        if augment:
            turns, mirror = int(rng.integers(4)), bool(rng.integers(2))
            map_crop, mask, target = (_turn(a, turns, mirror) for a in (map_crop, mask, target))
        return map_crop, mask, target


def _turn(array: np.ndarray, turns: int, mirror: bool) -> np.ndarray:
    """Rotate the last two axes by quarter turns, then mirror left-right if asked (contiguous copy)."""
    array = np.rot90(array, turns, axes=(-2, -1))
    return np.ascontiguousarray(array[..., ::-1] if mirror else array)
