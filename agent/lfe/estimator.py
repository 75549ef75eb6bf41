"""Frontier properties from the trained UNet: what the LFE planner uses when it has no oracle.

One call runs the network once over the known part of the map and reads every frontier's R_A,
D_in and D_out off its pixels. The map a robot builds is mostly unknown (a 48 m grid around a
10 m flat), so the network sees only the bounding box of the known cells plus a margin; beyond
the map's edges the window is filled with unknown cells, as the training crops were.

A frontier's pixels are those the training data mark (`agent.lfe.raster.frontier_pixel_mask`):
the coarse cells holding its cells that read as frontier on the coarse map, FREE next to UNKNOWN.
A frontier none of whose cells does (all of them share a coarse cell with a wall, say) keeps all
its coarse cells rather than going without an estimate.

A frontier's estimate is the mean of the predictions over its pixels, as in the paper (§V-B).
Every pixel of a frontier was trained towards the same value, so their predictions mostly
agree; where they do not (the ends of a long frontier, far from most of its context) the mean
keeps their disagreement in the estimate rather than betting on one side as a median would.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np
import torch

from agent.lfe.model import FrontierUNet, UNetConfig, encode_input, from_network, load_model, map_window
from agent.lfe.properties import FrontierProperties, frontier_cells_of
from agent.lfe.raster import UNKNOWN, coarse_cells, coarsening_factor, encode_map, frontier_pixel_mask
from agent.planning.frontier import Frontier

SHIPPED_MODEL = Path(__file__).resolve().parent.parent / "data" / "lfe-unet.pt"
"""The model shipped with homebot, trained by ``homebot lfe train``."""

MARGIN_M = 6.4
"""Unknown space kept around the known cells: about half the network's receptive field (≈ 14 m at
depth 4), enough for the network to see that the map ends there and to predict into it."""


class LearnedEstimator:
    """R_A, D_in and D_out of frontiers, predicted by a `FrontierUNet` from the occupancy map.

    Args:
        model: the network (put in eval mode on ``device``).
        config: its config.
        device: the torch device.
    """

    def __init__(self, model: FrontierUNet, config: UNetConfig, device: torch.device | str = "cpu") -> None:
        self.model = model.to(device).eval()
        self.config = config
        self.device = torch.device(device)

    @classmethod
    def load(cls, path: Path | None = None, device: str | None = None) -> LearnedEstimator:
        """The estimator of a model file (by default the one shipped with homebot), on ``device`` (cpu).

        Args:
            path: the model file (the shipped one when None).
            device: the torch device (cpu when None).

        Returns:
            The estimator.

        Raises:
            FileNotFoundError: no model file there.
            ModelFileError: the file is not a readable model.
        """
        path = SHIPPED_MODEL if path is None else Path(path)
        if not path.is_file():
            raise FileNotFoundError(f"{path}: no frontier-property model there; train one with "
                                    "`homebot lfe train` (and its training data with `homebot lfe --help`)")
        model, config, _ = load_model(path, device)
        return cls(model, config, device or "cpu")

    def estimate(self, free: np.ndarray, occupied: np.ndarray, resolution: float,
                 frontiers: Sequence[Frontier | np.ndarray]) -> list[FrontierProperties]:
        """One `FrontierProperties` per frontier, in order, from the known ``free`` and ``occupied`` cells.

        ``frontiers`` are `Frontier` objects or their (K, 2) cells at ``resolution``; the map is
        coarsened to the network's resolution by `encode_map`, which must divide evenly. Pass all
        of the map's frontiers, not a chosen few: the network was trained with every frontier
        marked in its input, and a frontier's neighbours are part of what it reads.

        Args:
            free: the known free cells.
            occupied: the known occupied cells.
            resolution: the map's cell size (m).
            frontiers: every frontier of the map.

        Returns:
            R_A, D_in and D_out of each frontier.
        """
        if len(frontiers) == 0:
            return []
        encoded = encode_map(free, occupied, resolution, self.config.model_resolution)
        factor = coarsening_factor(resolution, self.config.model_resolution)
        on_frontier = frontier_pixel_mask(encoded)
        pixels = [_frontier_pixels(coarse_cells(frontier_cells_of(frontier, np.shape(free)), factor), on_frontier)
                  for frontier in frontiers]
        corner, window = self._window(encoded, np.concatenate(pixels))
        mask = np.zeros(window.shape, dtype=bool)
        for cells in pixels:
            mask[tuple((cells - corner).T)] = True
        with torch.inference_mode():
            outputs = self.model(encode_input(window[None], mask[None]).to(self.device))[0]
            predicted = from_network(outputs).permute(1, 2, 0).cpu().numpy()  # (h, w, 3)
        means = [predicted[tuple((cells - corner).T)].mean(axis=0) for cells in pixels]
        return [FrontierProperties(*(float(v) for v in mean)) for mean in means]

    def _window(self, encoded: np.ndarray, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(top-left corner in map pixels, the window): the known cells and frontiers plus the margin.

        The window's sides are rounded up to the network's multiple, so it pads nothing with
        zeros itself; everything outside the map is unknown.
        """
        known = np.argwhere(encoded != UNKNOWN)
        cells = np.concatenate([known, pixels])
        margin = int(np.ceil(MARGIN_M / self.config.model_resolution))
        corner = cells.min(axis=0) - margin
        size = cells.max(axis=0) + margin + 1 - corner
        size = -(-size // self.config.multiple) * self.config.multiple
        return corner, map_window(encoded, corner, tuple(int(side) for side in size))



def _frontier_pixels(coarse: np.ndarray, on_frontier: np.ndarray) -> np.ndarray:
    """Those of a frontier's coarse cells that read as frontier, or all of them if none does."""
    kept = coarse[on_frontier[coarse[:, 0], coarse[:, 1]]]
    return kept if len(kept) else coarse
