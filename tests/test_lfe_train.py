"""Training the frontier-property UNet on tiny synthetic homes: loss, files, resume, split, crops."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import torch
from scipy import ndimage

from agent.lfe.model import UNetConfig, load_model
from agent.lfe.properties import label_frontiers
from agent.lfe.raster import FREE, encode_map
from agent.lfe.shards import shard_paths
from agent.lfe.train import TrainConfig, read_history, train
from agent.lfe.training_set import CropSampler, load_shard, split_homes
from agent.mapping.grid import GridSpec
from agent.planning.frontier import cluster_frontiers, frontier_cells

RES = 0.1
TINY = TrainConfig(model=UNetConfig(base_channels=4, depth=3), epochs=1, batch_size=4, crop=32, steps_per_epoch=6,
                   val_fraction=0.34, val_crops=8, max_minutes=None, device="cpu", threads=1)


def rooms(rng: np.random.Generator, shape: tuple[int, int] = (40, 56)) -> np.ndarray:
    """True free space of a small home: two rows of three rooms, one-cell walls, 3-cell doorways."""
    rows, cols = shape
    free = np.zeros(shape, dtype=bool)
    free[1:-1, 1:-1] = True
    split = int(rng.integers(12, rows - 12))
    walls = [int(rng.integers(10, cols // 2 - 4)), int(rng.integers(cols // 2 + 4, cols - 10))]
    free[split, :] = False
    free[:, walls] = False
    for low, high in zip([0, *walls], [*walls, cols - 1]):
        door = int(rng.integers(low + 1, high - 3))
        free[split, door:door + 3] = True
    for wall in walls:
        for low, high in ((0, split), (split, rows - 1)):
            door = int(rng.integers(low + 1, high - 3))
            free[door:door + 3, wall] = True
    return free


def explore(free: np.ndarray, rng: np.random.Generator, snapshots: int = 4, radius: int = 8) -> dict[str, np.ndarray]:
    """Shard arrays of a robot that sees ``radius`` cells through free space and walks to random frontiers."""
    seen = np.zeros_like(free)
    position = tuple(rng.choice(np.argwhere(free)))
    maps, pixels, targets = [], [], []
    for index in range(snapshots):
        start = np.zeros_like(free)
        start[position] = True
        reached = ndimage.binary_dilation(start, iterations=radius, mask=free)
        seen |= ndimage.binary_dilation(reached, structure=np.ones((3, 3), dtype=bool))
        known_free, known_occupied = free & seen, ~free & seen
        mask = frontier_cells(known_free, seen, known_occupied, min_unexplored_neighbours=1)
        frontiers = cluster_frontiers(GridSpec((0.0, 0.0), RES, free.shape), mask, seen, known_occupied, min_size=1)
        if not frontiers:
            break
        maps.append(encode_map(known_free, known_occupied, RES, RES))
        for frontier, props in zip(frontiers, label_frontiers(free, seen, frontiers, RES)):
            pixels.append(np.column_stack([np.full(len(frontier.cells), index), frontier.cells]))
            targets.append(np.tile([props.area_m2, props.d_in_m, props.d_out_m], (len(frontier.cells), 1)))
        position = frontiers[int(rng.integers(len(frontiers)))].centre
    return {"maps": np.stack(maps), "pixels": np.concatenate(pixels).astype(np.int32),
            "targets": np.concatenate(targets).astype(np.float32)}


def write_shard(directory: Path, seed: int) -> Path:
    """One synthetic home's shard in `agent.lfe.samples`'s format."""
    rng = np.random.default_rng(seed)
    path = directory / f"home-{seed:05d}.npz"
    np.savez_compressed(path, **explore(rooms(rng), rng), resolution=np.float64(RES), seed=np.int64(seed))
    return path


@pytest.fixture(scope="module")
def data_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    directory = tmp_path_factory.mktemp("shards")
    for seed in range(3):
        write_shard(directory, seed)
    return directory


class Recorder(list):
    """A progress callback that keeps every event."""

    def __call__(self, event: dict[str, Any]) -> None:
        self.append(event)

    def of(self, kind: str) -> list[dict[str, Any]]:
        return [event for event in self if event["event"] == kind]


# --- config and data -------------------------------------------------------------------------


@pytest.mark.parametrize(("values", "field"), [
    ({"epochs": 0}, "epochs"),
    ({"lr": 0.0}, "lr"),
    ({"lr_decay": 1.5}, "lr_decay"),
    ({"batch_size": 2.0}, "batch_size"),
    ({"crop": 30}, "crop"),
    ({"val_fraction": 1.0}, "val_fraction"),
    ({"max_minutes": -1.0}, "max_minutes"),
    ({"device": "abacus"}, "device"),
    ({"seed": -1}, "seed"),
])
def test_config_errors_name_the_field(values: dict, field: str) -> None:
    with pytest.raises(ValueError, match=f"^{field}:"):
        replace(TINY, **values)


def test_learning_rate_drops_tenfold_every_two_epochs() -> None:
    config = TrainConfig()
    assert [config.lr_at(epoch) for epoch in range(1, 7)] == pytest.approx([1e-3, 1e-3, 1e-4, 1e-4, 1e-5, 1e-5])


def test_split_is_by_home_disjoint_deterministic_and_never_empty() -> None:
    paths = [Path(f"home-{seed:05d}.npz") for seed in range(20)]
    train_homes, val_homes = split_homes(paths, 0.25, seed=7)
    assert len(val_homes) == 5 and set(train_homes).isdisjoint(val_homes)
    assert sorted(train_homes + val_homes) == paths
    assert split_homes(paths, 0.25, seed=7) == (train_homes, val_homes)
    assert split_homes(paths, 0.25, seed=8)[1] != val_homes
    assert [len(side) for side in split_homes(paths[:2], 0.01, seed=0)] == [1, 1]
    with pytest.raises(ValueError, match="at least two homes"):
        split_homes(paths[:1], 0.5, seed=0)


def test_shard_problems_name_the_file(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="no training shards"):
        shard_paths(tmp_path)
    bad = tmp_path / "home-00001.npz"
    np.savez(bad, maps=np.zeros((1, 4, 4), np.uint8), resolution=np.float64(RES))
    with pytest.raises(ValueError, match="home-00001.npz: pixels: missing"):
        load_shard(bad, RES)
    coarse = write_shard(tmp_path, 5)
    with pytest.raises(ValueError, match="home-00005.npz: .* at 0.1 m, the network reads 0.2 m"):
        load_shard(coarse, 0.2)


def test_crops_keep_map_mask_and_targets_aligned_through_augmentation(data_dir: Path) -> None:
    shards = [load_shard(path, RES) for path in shard_paths(data_dir)]
    known = np.unique(np.concatenate([shard.targets for shard in shards]), axis=0)
    batch = CropSampler(shards, crop=32).batch(np.random.default_rng(1), 16, augment=True)
    maps = batch.inputs[:, :3].argmax(dim=1)
    assert batch.mask.flatten(1).any(dim=1).all()  # every crop holds a frontier pixel
    assert (maps[batch.mask] == FREE).all()  # frontier pixels are free cells, however turned
    natural = torch.expm1(batch.targets.permute(0, 2, 3, 1)[batch.mask]).numpy()
    assert np.isclose(natural[:, None], known[None], rtol=1e-5).all(axis=2).any(axis=1).all()
    assert (batch.targets.permute(0, 2, 3, 1)[~batch.mask] == 0).all()


# --- training --------------------------------------------------------------------------------


def test_training_loss_falls(data_dir: Path, tmp_path: Path) -> None:
    events = Recorder()
    config = replace(TINY, model=UNetConfig(base_channels=8, depth=3), steps_per_epoch=60, lr=3e-3)
    train(data_dir, tmp_path, config, events)
    losses = [event["loss"] for event in events.of("step")]
    assert len(losses) == 60
    assert np.mean(losses[-5:]) < 0.5 * np.mean(losses[:5])


def test_a_run_writes_model_history_plot_and_baseline(data_dir: Path, tmp_path: Path) -> None:
    result = train(data_dir, tmp_path, replace(TINY, epochs=2))
    history = read_history(tmp_path / "history.jsonl")
    assert [line["epoch"] for line in history] == [1, 2] == [line["epoch"] for line in result.history]
    assert [line["lr"] for line in history] == pytest.approx([1e-3, 1e-3])
    assert set(history[0]["val_mae"]) == {"area_m2", "d_in_m", "d_out_m"}
    assert history[0]["baseline_val_loss"] == result.baseline["val_loss"] > 0
    assert (tmp_path / "loss.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    model, config, metadata = load_model(result.model_path)
    best = min(history, key=lambda line: line["val_loss"])
    assert config == TINY.model and metadata["epoch"] == result.best_epoch == best["epoch"]
    assert metadata["val_loss"] == best["val_loss"]
    assert set(metadata["homes"]["train"]).isdisjoint(metadata["homes"]["val"])


def test_a_rerun_resumes_and_ends_where_an_uninterrupted_run_ends(data_dir: Path, tmp_path: Path) -> None:
    straight = train(data_dir, tmp_path / "straight", replace(TINY, epochs=2))
    train(data_dir, tmp_path / "resumed", TINY)
    events = Recorder()
    resumed = train(data_dir, tmp_path / "resumed", replace(TINY, epochs=2), events)
    assert resumed.resumed_after == 1 and events.of("resume")[0]["epochs_done"] == 1
    assert {event["epoch"] for event in events.of("step")} == {2}
    assert [line["epoch"] for line in read_history(tmp_path / "resumed" / "history.jsonl")] == [1, 2]
    weights = [torch.load(tmp_path / run / "checkpoint.pt", weights_only=True)["model"] for run in ("straight", "resumed")]
    for name, value in weights[0].items():
        torch.testing.assert_close(weights[1][name], value, rtol=0, atol=0)
    assert [line["val_loss"] for line in resumed.history] == [line["val_loss"] for line in straight.history]


def test_a_finished_run_trains_no_more(data_dir: Path, tmp_path: Path) -> None:
    train(data_dir, tmp_path, TINY)
    events = Recorder()
    again = train(data_dir, tmp_path, TINY, events)
    assert again.resumed_after == 1 and not events.of("step")
    assert len(read_history(tmp_path / "history.jsonl")) == 1


def test_time_limit_cuts_the_epoch_short_and_the_rerun_goes_on(data_dir: Path, tmp_path: Path) -> None:
    events = Recorder()
    cut = train(data_dir, tmp_path, replace(TINY, epochs=2, max_minutes=1e-9), events)
    assert cut.stopped_early and events.of("time-limit")
    assert [(line["epoch"], line["steps"], line["cut_short"]) for line in cut.history] == [(1, 1, True)]
    assert (tmp_path / "model.pt").exists()
    rest = train(data_dir, tmp_path, replace(TINY, epochs=2))
    assert not rest.stopped_early
    assert [(line["epoch"], line["cut_short"]) for line in rest.history] == [(1, True), (2, False)]


def test_a_rerun_with_other_settings_is_refused(data_dir: Path, tmp_path: Path) -> None:
    train(data_dir, tmp_path, TINY)
    with pytest.raises(ValueError, match="checkpoint.pt was written with other config"):
        train(data_dir, tmp_path, replace(TINY, lr=1e-2))


def test_history_lines_are_plain_json(data_dir: Path, tmp_path: Path) -> None:
    train(data_dir, tmp_path, TINY)
    line = json.loads((tmp_path / "history.jsonl").read_text().splitlines()[0])
    assert {"epoch", "train_loss", "val_loss", "val_mae", "lr", "seconds", "baseline_val_loss"} <= set(line)
