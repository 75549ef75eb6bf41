"""Training shards: what they hold, that it matches the ground truth, and that generation resumes."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from agent.app.eval.lfe_data import generate_dataset
from agent.lfe.coverage import fbe_near, run_coverage
from agent.lfe.samples import DataConfig, home_samples
from agent.lfe.shards import load_shard, shard_path
from agent.lfe.properties import label_frontiers
from agent.lfe.raster import FREE, UNKNOWN, coarse_cells, encode_map, frontier_pixel_mask
from agent.lfe.task import CoverageConfig, Situation, TrueHome
from worlds.home import generate_home

SMALL_HOME = 27  # a 76 m² home of four rooms
QUICK = DataConfig(coverage=CoverageConfig(budget_steps=40), record_every=2)


@pytest.fixture(scope="module")
def samples() -> dict[str, np.ndarray]:
    return home_samples(SMALL_HOME, QUICK)


def test_samples_have_the_shard_layout(samples: dict[str, np.ndarray]) -> None:
    maps, pixels, targets = samples["maps"], samples["pixels"], samples["targets"]
    assert maps.dtype == np.uint8 and maps.ndim == 3 and len(maps) >= 3
    assert pixels.dtype == np.int32 and pixels.shape[1] == 3
    assert targets.dtype == np.float32 and targets.shape == (len(pixels), 3)
    assert samples["resolution"] == 0.1 and samples["seed"] == SMALL_HOME
    assert set(np.unique(pixels[:, 0])) == set(range(len(maps)))  # every snapshot has frontier pixels
    assert (np.diff(pixels[:, 0]) >= 0).all()
    assert len(np.unique(pixels, axis=0)) == len(pixels)  # one target per pixel
    # the maps cover the simulator's grid, which is the home's bounding box, at 0.1 m
    spec = TrueHome.from_home(generate_home(SMALL_HOME), QUICK.coverage, SMALL_HOME).spec
    x0, y0, x1, y1 = generate_home(SMALL_HOME).bounds
    assert spec.origin_xy == (x0, y0) and spec.extent()[1] >= x1 and spec.extent()[3] >= y1
    assert maps.shape[1:] == tuple(-(-n // 2) for n in spec.shape)
    # and the robot learns as it goes
    known = (maps != UNKNOWN).sum(axis=(1, 2))
    assert (np.diff(known) >= 0).all() and known[-1] > known[0]


def test_pixels_lie_on_frontier_pixels_of_their_map(samples: dict[str, np.ndarray]) -> None:
    for index, grid in enumerate(samples["maps"]):
        mine = samples["pixels"][samples["pixels"][:, 0] == index, 1:]
        assert (grid[mine[:, 0], mine[:, 1]] == FREE).all()
        padded = np.pad(grid, 1, constant_values=FREE)
        unknown_near = np.zeros(len(mine), dtype=bool)
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                unknown_near |= padded[mine[:, 0] + 1 + dr, mine[:, 1] + 1 + dc] == UNKNOWN
        assert unknown_near.all()
        assert frontier_pixel_mask(grid)[mine[:, 0], mine[:, 1]].all()


def test_targets_are_the_ground_truth_labels_of_the_recorded_snapshots() -> None:
    config = DataConfig(coverage=CoverageConfig(budget_steps=40), record_every=3, explore_noise=0.0)
    samples = home_samples(SMALL_HOME, config)
    # the same exploration again (no noise: plain FBE-Near), keeping every third situation
    home = TrueHome.from_home(generate_home(SMALL_HOME), config.coverage, SMALL_HOME)
    situations: list[Situation] = []
    run_coverage(home, fbe_near, config.coverage, on_plan=lambda s, _: situations.append(s))
    recorded = situations[::3]
    assert len(recorded) == len(samples["maps"])
    for index, situation in enumerate(recorded):
        np.testing.assert_array_equal(samples["maps"][index], encode_map(situation.free, situation.occupied, 0.05, 0.1))
        expected: dict[tuple[int, int], tuple[float, float, float]] = {}
        labels = label_frontiers(home.free, situation.observed, situation.frontiers, 0.05)
        on_frontier = frontier_pixel_mask(samples["maps"][index])
        for frontier, props in zip(situation.frontiers, labels):
            for row, col in coarse_cells(frontier.cells, 2):
                if on_frontier[row, col] and props.area_m2 > expected.get((row, col), (-1.0,))[0]:
                    expected[(row, col)] = (props.area_m2, props.d_in_m, props.d_out_m)
        mine = samples["pixels"][:, 0] == index
        got = {(int(r), int(c)): tuple(t) for (_, r, c), t in zip(samples["pixels"][mine], samples["targets"][mine])}
        assert got.keys() == expected.keys()
        for pixel, target in got.items():
            np.testing.assert_allclose(target, expected[pixel], rtol=1e-6)


def test_the_same_seed_gives_the_same_samples(samples: dict[str, np.ndarray]) -> None:
    again = home_samples(SMALL_HOME, QUICK)
    for name in samples:
        np.testing.assert_array_equal(samples[name], again[name])


def test_a_shard_round_trips_and_a_rerun_skips_finished_homes(tmp_path: Path) -> None:
    calls: list[tuple[int, int, int | None]] = []
    summary = generate_dataset(tmp_path, [SMALL_HOME], QUICK, progress=lambda *a: calls.append(a))
    path = shard_path(tmp_path, SMALL_HOME)
    assert summary.written == (SMALL_HOME,) and summary.skipped == ()
    assert calls == [(1, 1, summary.snapshots)] and summary.snapshots > 0
    shard = load_shard(path)
    fresh = home_samples(SMALL_HOME, QUICK)
    for name in fresh:
        np.testing.assert_array_equal(shard[name], fresh[name])
    assert shard["pixels"].dtype == np.int32 and shard["seed"].dtype == np.int64
    assert sorted(p.name for p in tmp_path.iterdir()) == [path.name]  # no temporary file left behind

    written_at = path.stat().st_mtime_ns
    calls.clear()
    rerun = generate_dataset(tmp_path, [SMALL_HOME], QUICK, progress=lambda *a: calls.append(a))
    assert rerun.written == () and rerun.skipped == (SMALL_HOME,)
    assert calls == [(1, 1, None)]  # skipped: no maps to count, no time to estimate from
    assert path.stat().st_mtime_ns == written_at


def test_an_interrupted_run_leaves_whole_shards_and_the_next_run_finishes(tmp_path: Path) -> None:
    config = DataConfig(coverage=CoverageConfig(budget_steps=10), record_every=1)
    seeds = [SMALL_HOME, 30]

    def stop(done: int, total: int, samples: int) -> None:
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        generate_dataset(tmp_path, seeds, config, progress=stop)
    assert [p.name for p in tmp_path.iterdir()] == [shard_path(tmp_path, SMALL_HOME).name]
    summary = generate_dataset(tmp_path, seeds, config)
    assert summary.skipped == (SMALL_HOME,) and summary.written == (30,)
    assert all(load_shard(shard_path(tmp_path, seed))["seed"] == seed for seed in seeds)


def test_workers_in_other_processes_write_the_same_shards(tmp_path: Path) -> None:
    config = DataConfig(coverage=CoverageConfig(budget_steps=10), record_every=1)
    seeds = [SMALL_HOME, 30]
    generate_dataset(tmp_path / "one", seeds, config, workers=1)
    summary = generate_dataset(tmp_path / "two", seeds, config, workers=2)
    assert sorted(summary.written) == seeds
    for seed in seeds:
        one, two = load_shard(shard_path(tmp_path / "one", seed)), load_shard(shard_path(tmp_path / "two", seed))
        for name in one:
            np.testing.assert_array_equal(one[name], two[name])


def _write(path: Path, samples: dict[str, np.ndarray], **changes: object) -> Path:
    arrays = {**samples, **changes}
    np.savez_compressed(path, **{name: value for name, value in arrays.items() if value is not None})
    return path


@pytest.mark.parametrize(("changes", "message"), [
    ({"pixels": "int64"}, "pixels: must be int32"),
    ({"targets": None}, "targets: missing"),
    ({"targets": "short"}, r"targets: must be \("),
    ({"maps": "values"}, "maps: values must be"),
    ({"pixels": "outside"}, "pixels: index outside maps"),
    ({"seed": "array"}, "seed: must be int64 with 0 dimensions"),
])
def test_a_malformed_shard_is_refused_naming_the_file_and_the_field(
        tmp_path: Path, samples: dict[str, np.ndarray], changes: dict[str, object], message: str) -> None:
    broken = {
        "int64": samples["pixels"].astype(np.int64),
        "short": samples["targets"][:-1],
        "values": np.full_like(samples["maps"], 7),
        "outside": samples["pixels"] + np.array([0, 1000, 0], dtype=np.int32),
        "array": np.array([SMALL_HOME], dtype=np.int64),
    }
    path = _write(tmp_path / "home-00027.npz", samples,
                  **{name: None if how is None else broken[how] for name, how in changes.items()})
    with pytest.raises(ValueError, match=f"home-00027.npz: {message}"):
        load_shard(path)


def test_a_file_that_is_no_shard_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "home-00001.npz"
    path.write_bytes(b"not a zip archive")
    with pytest.raises(ValueError, match="home-00001.npz: not a readable shard"):
        load_shard(path)


@pytest.mark.parametrize(("changes", "message"), [
    ({"record_every": 0}, "record_every: must be a positive integer, got 0"),
    ({"explore_noise": 1.5}, r"explore_noise: must be a probability in \[0, 1\], got 1.5"),
    ({"model_resolution": 0.07}, "model_resolution: .* do not tile"),
])
def test_data_config_names_the_bad_field(changes: dict[str, object], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        DataConfig(**changes)
