"""Training samples for the frontier-property network, one home at a time (paper §V-B).

"Generated from many seeded homes by running plain frontier exploration and recording partial
maps with frontier labels": each home of `worlds.home.generate_home` is explored once by FBE-Near
in the coverage simulator (`agent.lfe.coverage`), with a seeded chance of taking a random frontier
instead so that the recorded maps are not all of one kind. Every few planning steps the partial
map is recorded at the network's resolution together with every offered frontier's ground-truth
R_A, D_in and D_out (`agent.lfe.properties`), written on the frontier's pixels.

The arrays of one home make one shard (`agent.lfe.shards`): the snapshots and the frontier
pixels' targets; the maps span the home's bounding box (the simulator's grid, so no crop is
needed), and of two frontiers sharing a pixel the one with the larger R_A labels it.

A frontier pixel is a coarse cell holding one of the frontier's cells that also reads as a
frontier on the coarse map (FREE, with an UNKNOWN 8-neighbour, `frontier_pixel_mask`): a fine frontier
cell can share its coarse cell with an obstacle or have its unknown neighbours inside that cell,
and the network cannot tell such a pixel from the space around it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from agent.lfe.coverage import fbe_near, run_coverage
from agent.lfe.properties import label_frontiers
from agent.lfe.raster import coarse_cells, coarsening_factor, encode_map, frontier_pixel_mask
from agent.lfe.task import CoverageConfig, FrontierChooser, Situation, TrueHome
from worlds.home import generate_home

MODEL_RESOLUTION = 0.1
"""The network's cells (m): the EQA tree's map is at 0.1 m too, so one network serves both."""

_NOISE_STREAM = 1  # the explorer's random choices use stream (seed, 1); the start pose uses the seed itself


@dataclass(frozen=True)
class DataConfig:
    """How the training data are made.

    A 500-step exploration makes 100–150 planning steps (one every five steps or sooner), so a
    snapshot every fourth gives some 25–40 maps per home, a few steps of travel apart: nearer
    snapshots would mostly repeat each other. One choice in five is a random frontier: enough to
    send the robot across the home now and then, while keeping the maps those of an explorer.

    Args:
        coverage: the exploration that is recorded.
        record_every: planning steps between recorded snapshots (the first is recorded).
        explore_noise: chance of choosing a random frontier instead of the nearest.
        model_resolution: the network's cells (m); a whole multiple of the exploration's.

    Raises:
        ValueError: ``record_every`` not a positive integer, ``explore_noise`` not a probability,
            or a resolution that is not a whole multiple of the exploration's.
    """

    coverage: CoverageConfig = CoverageConfig()
    record_every: int = 4
    explore_noise: float = 0.2
    model_resolution: float = MODEL_RESOLUTION

    def __post_init__(self) -> None:
        if isinstance(self.record_every, bool) or not isinstance(self.record_every, (int, np.integer)) \
                or self.record_every <= 0:
            raise ValueError(f"record_every: must be a positive integer, got {self.record_every!r}")
        if not (isinstance(self.explore_noise, (int, float)) and 0.0 <= self.explore_noise <= 1.0):
            raise ValueError(f"explore_noise: must be a probability in [0, 1], got {self.explore_noise!r}")
        try:
            coarsening_factor(self.coverage.resolution, self.model_resolution)
        except ValueError as error:
            raise ValueError(f"model_resolution: {error}") from None


def home_samples(seed: int, config: DataConfig = DataConfig()) -> dict[str, np.ndarray]:
    """Explore the home of ``seed`` once and record its training samples (see the module's docstring).

    The home, the start pose and every random choice of the explorer come from ``seed``: the same
    seed and config give the same arrays.

    Args:
        seed: the home's seed (`worlds.home.generate_home`), its start pose's and the explorer's.
        config: how the exploration runs and what it records.

    Returns:
        The arrays of the home's shard (`agent.lfe.shards.SHARD_ARRAYS`).
    """
    home = TrueHome.from_home(generate_home(seed), config.coverage, seed)
    recorder = _Recorder(home, config)
    chooser = _noisy_nearest(np.random.default_rng([seed, _NOISE_STREAM]), config.explore_noise)
    run_coverage(home, chooser, config.coverage, on_plan=recorder)
    return recorder.arrays(seed)


class _Recorder:
    """The ``on_plan`` hook that records every ``record_every``-th planning step as a snapshot."""

    def __init__(self, home: TrueHome, config: DataConfig) -> None:
        self.home = home
        self.config = config
        self.factor = coarsening_factor(config.coverage.resolution, config.model_resolution)
        self.plans = 0
        self.maps: list[np.ndarray] = []
        self.pixels: list[np.ndarray] = []
        self.targets: list[np.ndarray] = []

    def __call__(self, situation: Situation, chosen: int) -> None:
        plan = self.plans
        self.plans += 1
        if plan % self.config.record_every:
            return
        encoded = encode_map(situation.free, situation.occupied, situation.spec.resolution,
                             self.config.model_resolution)
        labels = label_frontiers(self.home.free, situation.observed, situation.frontiers, situation.spec.resolution)
        on_frontier = frontier_pixel_mask(encoded)
        pixels, targets = [], []
        for frontier, properties in zip(situation.frontiers, labels):
            coarse = coarse_cells(frontier.cells, self.factor)
            mine = coarse[on_frontier[coarse[:, 0], coarse[:, 1]]]
            pixels.append(mine)
            targets.append(np.tile([properties.area_m2, properties.d_in_m, properties.d_out_m], (len(mine), 1)))
        pixels_, targets_ = _largest_area_per_pixel(np.concatenate(pixels), np.concatenate(targets))
        if not len(pixels_):
            return  # nothing for the loss to read
        snapshot = np.full((len(pixels_), 1), len(self.maps))
        self.maps.append(encoded)
        self.pixels.append(np.hstack([snapshot, pixels_]))
        self.targets.append(targets_)

    def arrays(self, seed: int) -> dict[str, np.ndarray]:
        rows, cols = self.maps[0].shape if self.maps else (0, 0)
        return {
            "maps": np.array(self.maps, dtype=np.uint8).reshape(len(self.maps), rows, cols),
            "pixels": np.concatenate(self.pixels).astype(np.int32) if self.pixels else np.zeros((0, 3), np.int32),
            "targets": np.concatenate(self.targets).astype(np.float32) if self.targets
            else np.zeros((0, 3), np.float32),
            "resolution": np.float64(self.config.model_resolution),
            "seed": np.int64(seed),
        }


def _largest_area_per_pixel(pixels: np.ndarray, targets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One row per distinct pixel, in row-major order: of rows sharing a pixel, the largest R_A."""
    if not len(pixels):
        return pixels.reshape(0, 2), targets.reshape(0, 3)
    order = np.lexsort((-targets[:, 0], pixels[:, 1], pixels[:, 0]))
    pixels, targets = pixels[order], targets[order]
    first = np.ones(len(pixels), dtype=bool)
    first[1:] = (pixels[1:] != pixels[:-1]).any(axis=1)
    return pixels[first], targets[first]


def _noisy_nearest(rng: np.random.Generator, noise: float) -> FrontierChooser:
    """FBE-Near, except that with chance ``noise`` a frontier drawn uniformly from ``rng``."""

    def choose(situation: Situation) -> int:
        if rng.random() < noise:
            return int(rng.integers(len(situation.frontiers)))
        return fbe_near(situation)

    return choose
