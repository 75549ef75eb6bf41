"""Training data for the frontier-property network (paper §V-B).

"Generated from many seeded homes by running plain frontier exploration and recording partial
maps with frontier labels": each home of `worlds.home.generate_home` is explored once by FBE-Near
in the coverage simulator (`agent.lfe.coverage`), with a seeded chance of taking a random frontier
instead so that the recorded maps are not all of one kind. Every few planning steps the partial
map is recorded at the network's resolution together with every offered frontier's ground-truth
R_A, D_in and D_out (`agent.lfe.properties`), written on the frontier's pixels.

One compressed shard per home (`agent.lfe.shards`) holds the snapshots and the frontier pixels'
targets; the maps span the home's bounding box (the simulator's grid, so no crop is needed), and of
two frontiers sharing a pixel the one with the larger R_A labels it.

A frontier pixel is a coarse cell holding one of the frontier's cells that also reads as a
frontier on the coarse map (FREE, with an UNKNOWN 8-neighbour, `frontier_pixel_mask`): a fine frontier
cell can share its coarse cell with an obstacle or have its unknown neighbours inside that cell,
and the network cannot tell such a pixel from the space around it.

Shards are written whole (a temporary file, then a rename), so a run that is stopped leaves no
half shard, and a rerun skips the homes whose shard is there.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from agent.lfe.coverage import CoverageConfig, FrontierChooser, Situation, TrueHome, fbe_near, run_coverage
from agent.lfe.properties import label_frontiers
from agent.app.runtime.pool import as_finished
from agent.lfe.shards import shard_path, write_shard
from agent.lfe.raster import coarse_cells, coarsening_factor, encode_map, frontier_pixel_mask
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
    """

    coverage: CoverageConfig = CoverageConfig()
    record_every: int = 4  # planning steps between recorded snapshots (the first is recorded)
    explore_noise: float = 0.2  # chance of choosing a random frontier instead of the nearest
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


@dataclass(frozen=True)
class DatasetSummary:
    """What one `generate_dataset` call did."""

    out_dir: Path
    written: tuple[int, ...]  # seeds whose shard this call wrote, in the order they finished
    skipped: tuple[int, ...]  # seeds whose shard was there already
    snapshots: int  # maps in the shards written
    pixels: int  # frontier pixels in them
    seconds: float

    def __str__(self) -> str:
        return (f"{self.out_dir}: {len(self.written)} homes written ({self.snapshots} maps, {self.pixels} frontier "
                f"pixels), {len(self.skipped)} already there, {self.seconds:.0f} s")


def home_samples(seed: int, config: DataConfig = DataConfig()) -> dict[str, np.ndarray]:
    """Explore the home of ``seed`` once and return its shard's arrays (see the module's docstring).

    The home, the start pose and every random choice of the explorer come from ``seed``: the same
    seed and config give the same arrays.
    """
    home = TrueHome.from_home(generate_home(seed), config.coverage, seed)
    recorder = _Recorder(home, config)
    chooser = _noisy_nearest(np.random.default_rng([seed, _NOISE_STREAM]), config.explore_noise)
    run_coverage(home, chooser, config.coverage, on_plan=recorder)
    return recorder.arrays(seed)


def generate_dataset(out_dir: Path, seeds: Sequence[int], config: DataConfig = DataConfig(), workers: int = 1,
                     progress: Callable[[int, int, int | None], None] | None = None) -> DatasetSummary:
    """Write one shard per seed into ``out_dir``, skipping the seeds whose shard is there.

    ``progress(done, total, samples)`` is called once per home, skipped ones first, with the maps
    this call recorded in it (None for a skipped home, so that an estimate of the time left can
    leave those out). With ``workers`` > 1, homes are explored in
    that many processes and each shard is written as its home finishes; if one home fails, the
    shards already written stay, so a rerun picks up where this one stopped.
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers: must be a positive integer, got {workers!r}")
    unique = list(dict.fromkeys(int(seed) for seed in seeds))
    if any(seed < 0 for seed in unique):
        raise ValueError(f"seeds: must not be negative, got {min(unique)}")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    there = {seed for seed in unique if shard_path(out_dir, seed).exists()}
    skipped = [seed for seed in unique if seed in there]
    todo = [seed for seed in unique if seed not in there]
    done = 0
    for _ in skipped:
        done += 1
        if progress is not None:
            progress(done, len(unique), None)
    written, snapshots, pixels = [], 0, 0
    for (seed, _), arrays in as_finished(home_samples, [(seed, config) for seed in todo], workers):
        write_shard(shard_path(out_dir, seed), arrays)
        written.append(seed)
        snapshots += len(arrays["maps"])
        pixels += len(arrays["pixels"])
        done += 1
        if progress is not None:
            progress(done, len(unique), len(arrays["maps"]))
    return DatasetSummary(out_dir, tuple(written), tuple(skipped), snapshots, pixels, time.monotonic() - started)


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
