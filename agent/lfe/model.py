"""The frontier-property network: a UNet from the occupancy map to R_A, D_in and D_out per pixel.

As in the paper (§V-B), the network reads the observed map and writes a map of the same size with
three channels; only the frontier pixels carry targets, and a frontier's estimate is read off its
pixels. The input is the map one-hot (unknown, occupied, free, as `agent.lfe.raster` encodes it)
plus a fourth channel marking the frontier pixels, so the network knows where it will be asked.

Targets are learned as ``log1p`` of their natural units (m², m, m): areas beyond a frontier range
from a 2 m² closet to a 200 m² wing, and an L1 loss on raw values would only listen to the wings.
`to_network` and `from_network` convert; everything outside this module sees natural units.

A model file holds the `UNetConfig`, the weights and a free-form, JSON-able metadata dict (what
it was trained on and how well it did). It is read with ``torch.load(weights_only=True)``, so
opening a model file never runs code from it.
"""

from __future__ import annotations

import json
import os
import pickle
import zipfile
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from agent.lfe.raster import FREE, UNKNOWN

FILE_FORMAT = "homebot-lfe-unet/1"
"""Written into every model file; a file with another value is refused rather than misread."""

TARGETS = ("area_m2", "d_in_m", "d_out_m")
"""The output channels, in order: R_A (m²), D_in (m), D_out (m)."""

_MAP_CLASSES = FREE + 1  # unknown, occupied, free


class ModelFileError(ValueError):
    """A model or checkpoint file that exists but cannot be used: corrupt, foreign or incompatible."""


@dataclass(frozen=True)
class UNetConfig:
    """The network's shape and the grid it reads.

    ``depth`` counts resolution levels: 4 levels pool three times, so each bottleneck pixel sees
    8×8 map pixels and the receptive field spans about 14 m at 0.1 m cells, room-scale context.
    With ``base_channels`` 16 the widths are 16, 32, 64, 128 and the weights take about 2 MB.
    """

    in_channels: int = 4
    out_channels: int = 3
    base_channels: int = 16
    depth: int = 4
    model_resolution: float = 0.1

    def __post_init__(self) -> None:
        if self.in_channels != _MAP_CLASSES + 1:
            raise ValueError(f"in_channels: {self.in_channels!r} must be {_MAP_CLASSES + 1} "
                             "(unknown, occupied, free and the frontier mask)")
        if self.out_channels != len(TARGETS):
            raise ValueError(f"out_channels: {self.out_channels!r} must be {len(TARGETS)} ({', '.join(TARGETS)})")
        _require_int(self.base_channels, "base_channels", 1)
        _require_int(self.depth, "depth", 1)
        if not (isinstance(self.model_resolution, (int, float)) and np.isfinite(self.model_resolution)
                and self.model_resolution > 0):
            raise ValueError(f"model_resolution: {self.model_resolution!r} must be a positive number of metres")

    @property
    def multiple(self) -> int:
        """Input sides are padded to a multiple of this, so every pooling halves them exactly."""
        return 2 ** (self.depth - 1)

    def to_dict(self) -> dict[str, Any]:
        """The config as plain data, for model files.

        Returns:
            The dict.
        """
        return asdict(self)

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> UNetConfig:
        """The config from `to_dict`'s output; unknown keys are an error, not silently dropped.

        Args:
            values: the dict.

        Returns:
            The config.

        Raises:
            ValueError: an unknown key.
        """
        unknown = set(values) - {f.name for f in fields(cls)}
        if unknown:
            raise ValueError(f"unknown UNetConfig fields: {', '.join(sorted(unknown))}")
        return cls(**values)


def _require_int(value: Any, name: str, minimum: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
        raise ValueError(f"{name}: {value!r} must be an integer of at least {minimum}")


def to_network(targets: torch.Tensor | np.ndarray) -> torch.Tensor:
    """Natural units (m², m, m) -> the values the network learns (log1p, so every scale counts).

    Args:
        targets: R_A, D_in, D_out in natural units.

    Returns:
        The network's units.
    """
    return torch.log1p(torch.as_tensor(targets, dtype=torch.float32))


def from_network(outputs: torch.Tensor) -> torch.Tensor:
    """The network's outputs -> natural units, clipped at zero (no area or length is negative).

    Args:
        outputs: the network's outputs.

    Returns:
        Natural units.
    """
    return torch.expm1(outputs).clamp_min(0.0)


def encode_input(maps: torch.Tensor | np.ndarray, frontier_mask: torch.Tensor | np.ndarray) -> torch.Tensor:
    """(B, 4, H, W) float input: one-hot unknown / occupied / free, then the frontier pixels.

    ``maps`` holds `encode_map` values (B, H, W); ``frontier_mask`` is true (or 1) on frontier pixels.

    Args:
        maps: the encoded maps (B, H, W).
        frontier_mask: the frontier pixels (B, H, W).

    Returns:
        The input.

    Raises:
        ValueError: shapes that differ or a map value out of range.
    """
    maps = torch.as_tensor(maps)
    mask = torch.as_tensor(frontier_mask)
    if maps.ndim != 3 or mask.shape != maps.shape:
        raise ValueError(f"maps {tuple(maps.shape)} and frontier_mask {tuple(mask.shape)} must both be (B, H, W)")
    maps = maps.long()
    if maps.numel() and (maps.min() < 0 or maps.max() >= _MAP_CLASSES):
        raise ValueError(f"maps must hold encode_map values 0..{_MAP_CLASSES - 1}")
    one_hot = F.one_hot(maps, _MAP_CLASSES).permute(0, 3, 1, 2)
    return torch.cat([one_hot, mask.unsqueeze(1).bool()], dim=1).float()


def map_window(encoded: np.ndarray, corner: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """The ``size`` window of an encoded map from ``corner`` (row, col), unknown where it leaves the map.

    Training crops and the estimator's view of a map are both cut this way, so the network meets
    the map's edges the same way in both.

    Args:
        encoded: the encoded map.
        corner: the window's top-left cell (may lie off the map).
        size: the window's (rows, cols).

    Returns:
        The window.
    """
    window = np.full(size, UNKNOWN, dtype=np.uint8)
    corner = np.asarray(corner)
    low, high = np.maximum(corner, 0), np.minimum(corner + size, encoded.shape)
    if (high > low).all():
        window[low[0] - corner[0]:high[0] - corner[0], low[1] - corner[1]:high[1] - corner[1]] = \
            encoded[low[0]:high[0], low[1]:high[1]]
    return window


class _DoubleConv(nn.Sequential):
    """Two 3×3 convolutions, each with batch norm and ReLU: one UNet level."""

    def __init__(self, in_channels: int, out_channels: int) -> None:
        super().__init__(
            nn.Conv2d(in_channels, out_channels, 3, padding=1, bias=False),
            nn.BatchNorm2d(out_channels),
            nn.ReLU(inplace=True),
            nn.Conv2d(out_channels, out_channels, 3, padding=1, bias=False),
            nn.BatchNorm2d(out_channels),
            nn.ReLU(inplace=True),
        )


class FrontierUNet(nn.Module):
    """A classic UNet: max-pool down, transposed convolutions up, skips concatenated.

    Batch norm rather than group norm: at inference it applies the training statistics, so a
    pixel's output depends only on the map around it and not on how large a window was cut out.
    Inputs of any size are padded (with zeros) to a multiple of ``config.multiple`` and the output
    is cropped back; callers that can should pad with unknown map cells themselves, which is what
    the network saw around the edges during training.

    Args:
        config: the channels, depth and padding multiple.
    """

    def __init__(self, config: UNetConfig) -> None:
        super().__init__()
        self.config = config
        widths = [config.base_channels * 2**level for level in range(config.depth)]
        self.down = nn.ModuleList(_DoubleConv(c_in, c_out)
                                  for c_in, c_out in zip([config.in_channels, *widths], widths))
        self.up = nn.ModuleList(nn.ConvTranspose2d(wide, narrow, 2, stride=2)
                                for narrow, wide in zip(widths, widths[1:]))
        self.merge = nn.ModuleList(_DoubleConv(2 * narrow, narrow) for narrow in widths[:-1])
        self.head = nn.Conv2d(widths[0], config.out_channels, 1)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """(B, in_channels, H, W) -> (B, out_channels, H, W) in network units (see `from_network`).

        Args:
            x: the input (`encode_input`).

        Returns:
            The outputs.
        """
        height, width = x.shape[-2:]
        multiple = self.config.multiple
        x = F.pad(x, (0, -width % multiple, 0, -height % multiple))
        skips = []
        for level, block in enumerate(self.down):
            x = block(F.max_pool2d(x, 2) if level else x)
            skips.append(x)
        x = skips.pop()
        for up, merge in zip(reversed(self.up), reversed(self.merge)):
            x = merge(torch.cat([skips.pop(), up(x)], dim=1))
        return self.head(x)[..., :height, :width]


def save_model(path: Path, model: FrontierUNet, config: UNetConfig, metadata: dict[str, Any]) -> None:
    """Write config, weights and metadata to one file, atomically (a reader never sees half a file).

    Args:
        path: the file.
        model: the network.
        config: its config.
        metadata: what to keep with it (JSON-able).

    Raises:
        ValueError: metadata that is not JSON-able.
    """
    try:
        json.dumps(metadata)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"metadata must be JSON-able (it is stored as plain data): {exc}") from None
    contents = {"format": FILE_FORMAT, "config": config.to_dict(), "metadata": metadata,
                "state_dict": {k: v.detach().cpu() for k, v in model.state_dict().items()}}
    atomic_save(contents, Path(path))


def load_model(path: Path, device: str | torch.device | None = None) -> tuple[FrontierUNet, UNetConfig, dict[str, Any]]:
    """(model in eval mode on ``device`` (default cpu), its config, its metadata) from `save_model`'s file.

    Args:
        path: the file.
        device: the torch device (cpu when None).

    Returns:
        The model, its config and its metadata.

    Raises:
        FileNotFoundError: no such file.
        ModelFileError: the file is corrupt or not a model file.
    """
    path = Path(path)
    contents = load_plain(path)
    if contents.get("format") != FILE_FORMAT:
        raise ModelFileError(f"{path}: not a {FILE_FORMAT} model file (format {contents.get('format')!r})")
    try:
        config = UNetConfig.from_dict(contents["config"])
        model = FrontierUNet(config)
        model.load_state_dict(contents["state_dict"])
        metadata = dict(contents["metadata"])
    except (KeyError, TypeError, ValueError, RuntimeError) as exc:
        raise ModelFileError(f"{path}: incompatible model file: {exc}") from None
    return model.to(device or "cpu").eval(), config, metadata


def atomic_save(contents: dict[str, Any], path: Path) -> None:
    """``torch.save`` through a temporary file and a rename, so an interrupted write leaves the old file.

    Args:
        contents: what to save.
        path: the file.
    """
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_name(path.name + ".partial")
    torch.save(contents, partial)
    os.replace(partial, path)


def load_plain(path: Path) -> dict[str, Any]:
    """A dict written by `atomic_save`, read without running code; clear errors naming the path.

    Args:
        path: the file.

    Returns:
        The dict.

    Raises:
        FileNotFoundError: no such file.
        ModelFileError: the file is corrupt or not a torch file.
    """
    if not path.is_file():
        raise FileNotFoundError(f"{path}: no such file")
    try:
        contents = torch.load(path, map_location="cpu", weights_only=True)
    except (RuntimeError, EOFError, OSError, pickle.UnpicklingError, zipfile.BadZipFile) as exc:
        raise ModelFileError(f"{path}: corrupt or not a torch file ({exc})") from None
    if not isinstance(contents, dict):
        raise ModelFileError(f"{path}: holds a {type(contents).__name__}, not a dict")
    return contents
