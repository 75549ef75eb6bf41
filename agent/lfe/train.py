"""Training the frontier-property UNet on shards of explored homes.

The data are one ``home-NNNNN.npz`` per home (written by `agent.lfe.data`): the encoded maps of
the snapshots taken while a robot explored it, and the frontier pixels of each snapshot with
their ground-truth R_A, D_in and D_out. Training follows the paper (§VI): Adam at 1e-3, divided
by ten every two epochs, six epochs, an L1 loss on the frontier pixels only.

What differs is the budget: a few thousand snapshots and half an hour on a laptop CPU instead of
220,000 tuples and twelve GPU hours. So each step sees a batch of crops of the map (``crop``
pixels a side, 12.8 m at 0.1 m cells) centred near a random frontier pixel, turned and mirrored
at random (the properties do not change when the house does), and an epoch is a fixed number of
steps rather than a pass over the data.

Homes, not snapshots, are held out for validation: snapshots of one home share its layout, and a
network validated on the home it trained on would look better than it is. Validation runs on a
fixed set of crops of the held-out homes, next to a baseline that predicts the training median
everywhere, so the history shows whether the network learned anything beyond the typical value.

A run writes into ``out_dir``: ``model.pt`` (the best epoch by validation loss), ``history.jsonl``
(one line per finished epoch), ``loss.png`` and ``checkpoint.pt``. Running the same command again
continues after the last finished epoch; each epoch draws its crops from a generator seeded by
(seed, epoch), so a resumed run ends with the same weights as one that never stopped (on CPU).
"""

from __future__ import annotations

import json
import math
import time
import zlib
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from agent.lfe import shards
from agent.lfe.model import (
    TARGETS,
    FrontierUNet,
    ModelFileError,
    UNetConfig,
    atomic_save,
    encode_input,
    from_network,
    load_plain,
    map_window,
    save_model,
    to_network,
)

CHECKPOINT_FORMAT = "homebot-lfe-checkpoint/1"

Progress = Callable[[dict[str, Any]], None]


@dataclass(frozen=True)
class TrainConfig:
    """How to train. All fields but ``epochs``, ``max_minutes``, ``device`` and ``threads`` decide
    the weights each epoch ends with (see `outcome_fields`).

    ``steps_per_epoch`` × ``batch_size`` crops make an epoch. ``max_minutes`` bounds one
    invocation: the epoch under way is cut short, validated and kept, and no new epoch starts
    after it. ``device`` "auto" takes CUDA when there is one. ``threads`` 0 leaves torch's own
    choice (every core); on a machine shared with other work, 1 can be faster, because torch's
    threads spin waiting for each other when a core is taken away.
    """

    model: UNetConfig = field(default_factory=UNetConfig)
    epochs: int = 6
    lr: float = 1e-3
    lr_decay: float = 0.1
    lr_decay_every: int = 2
    batch_size: int = 16
    crop: int = 128
    steps_per_epoch: int = 120
    val_fraction: float = 0.1
    val_crops: int = 128
    seed: int = 0
    max_minutes: float | None = 30.0
    device: str = "auto"
    threads: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.model, UNetConfig):
            raise ValueError(f"model: {self.model!r} must be a UNetConfig")
        for name, minimum in (("epochs", 1), ("lr_decay_every", 1), ("batch_size", 1), ("crop", 1),
                              ("steps_per_epoch", 1), ("val_crops", 1), ("seed", 0), ("threads", 0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < minimum:
                raise ValueError(f"{name}: {value!r} must be an integer of at least {minimum}")
        if self.crop % self.model.multiple:
            raise ValueError(f"crop: {self.crop} must be a multiple of {self.model.multiple} "
                             f"(2 ** (depth - 1), so the UNet's poolings divide it)")
        _require_number(self.lr, "lr", low=0.0)
        _require_number(self.lr_decay, "lr_decay", low=0.0, high=1.0, high_inclusive=True)
        _require_number(self.val_fraction, "val_fraction", low=0.0, high=1.0)
        if self.max_minutes is not None:
            _require_number(self.max_minutes, "max_minutes", low=0.0)
        try:
            torch.device("cpu" if self.device == "auto" else self.device)
        except (RuntimeError, TypeError):
            raise ValueError(f"device: {self.device!r} is not 'auto' or a torch device such as 'cpu' or 'cuda'") from None

    def lr_at(self, epoch: int) -> float:
        """The learning rate of a 1-based epoch: ``lr``, times ``lr_decay`` after every ``lr_decay_every`` epochs."""
        return self.lr * self.lr_decay ** ((epoch - 1) // self.lr_decay_every)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def outcome_fields(self) -> dict[str, Any]:
        """The fields that decide the weights of each epoch: a resumed run must agree on all of them.

        ``epochs`` is not one of them, so a finished run can be extended by asking for more.
        """
        values = self.to_dict()
        for name in ("epochs", "max_minutes", "device", "threads"):
            del values[name]
        return values


def _require_number(value: Any, name: str, low: float, high: float = math.inf, high_inclusive: bool = False) -> None:
    """A finite number above ``low`` and below ``high`` (or up to it), else an error naming the field."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value > low
    ok = ok and (value <= high if high_inclusive else value < high)
    if not ok:
        bound = "" if math.isinf(high) else f" and {'at most' if high_inclusive else 'below'} {high:g}"
        raise ValueError(f"{name}: {value!r} must be a number above {low:g}{bound}")


@dataclass(frozen=True)
class TrainResult:
    """What a call to `train` left behind and how good it is."""

    model_path: Path
    history: list[dict[str, Any]]  # every finished epoch, resumed ones included
    best_epoch: int
    baseline: dict[str, Any]  # the training median's validation loss and MAE per channel
    resumed_after: int  # epochs finished before this call (0: a fresh start)
    stopped_early: bool  # the time limit cut this call short; run again to continue


# --- data ------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Shard:
    """One home's snapshots, with the frontier pixels of snapshot ``s`` at rows ``starts[s]:starts[s+1]``."""

    name: str
    maps: np.ndarray  # uint8 (S, H, W)
    pixels: np.ndarray  # int (P, 2) row, col, grouped by snapshot
    targets: np.ndarray  # float32 (P, 3) natural units
    starts: np.ndarray  # (S + 1,) offsets into pixels per snapshot

    def frontier_pixels(self, snapshot: int) -> tuple[np.ndarray, np.ndarray]:
        """(pixels (K, 2), targets (K, 3)) of one snapshot."""
        rows = slice(self.starts[snapshot], self.starts[snapshot + 1])
        return self.pixels[rows], self.targets[rows]


def load_shard(path: Path, model_resolution: float) -> Shard:
    """Read and check one home's shard (`agent.lfe.shards.load_shard`) at the network's resolution."""
    arrays = shards.load_shard(path)
    resolution = float(arrays["resolution"])
    if not math.isclose(resolution, model_resolution):
        raise ValueError(f"{path}: maps are at {resolution:g} m, the network reads {model_resolution:g} m")
    pixels = arrays["pixels"]
    starts = np.searchsorted(pixels[:, 0], np.arange(len(arrays["maps"]) + 1))
    return Shard(Path(path).stem, arrays["maps"], pixels[:, 1:].astype(np.int64), arrays["targets"], starts)


def split_homes(paths: Sequence[Path], val_fraction: float, seed: int) -> tuple[list[Path], list[Path]]:
    """(training, validation) shards: whole homes, at least one on each side.

    Each home draws a number from a generator seeded by (seed, its name) and the lowest go to
    validation, so the split depends on the seed and the names only, and adding homes moves few
    of the old ones across.
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
    """Network inputs (B, 4, C, C), targets in network units (B, 3, C, C) and the frontier mask (B, C, C)."""

    inputs: torch.Tensor
    targets: torch.Tensor
    mask: torch.Tensor

    def to(self, device: torch.device) -> Batch:
        return Batch(self.inputs.to(device), self.targets.to(device), self.mask.to(device))


class CropSampler:
    """Crops of snapshots centred near a frontier pixel, padded with unknown beyond the map.

    Snapshots are drawn uniformly (each with at least one frontier pixel), then one of their
    frontier pixels, then an offset of up to a quarter crop so the frontier is not always centred.
    """

    def __init__(self, shards: Sequence[Shard], crop: int) -> None:
        self.shards = list(shards)
        self.crop = crop
        self.snapshots = [(h, s) for h, shard in enumerate(self.shards)
                          for s in range(len(shard.maps)) if shard.starts[s + 1] > shard.starts[s]]
        if not self.snapshots:
            raise ValueError(f"no frontier pixels in homes {', '.join(s.name for s in self.shards)}")

    def batch(self, rng: np.random.Generator, size: int, augment: bool) -> Batch:
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


# --- training --------------------------------------------------------------------------------


def masked_l1(outputs: torch.Tensor, targets: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """Mean absolute error over frontier pixels and the three channels (network units)."""
    return (outputs - targets).abs().mean(dim=1)[mask].mean()


@dataclass(frozen=True)
class _Validation:
    """The fixed validation crops, evaluated in mini-batches, and the baseline they are compared with."""

    batches: list[Batch]
    median: torch.Tensor  # (3,) training median, natural units

    def evaluate(self, model: FrontierUNet, device: torch.device) -> dict[str, Any]:
        """Validation L1 (network units) and MAE per channel (natural units) of the model."""
        model.eval()
        with torch.inference_mode():
            outputs = [model(batch.inputs.to(device)).cpu() for batch in self.batches]
        return self._score(outputs)

    def baseline(self) -> dict[str, Any]:
        """The same scores for predicting the training median at every pixel."""
        constant = to_network(self.median)[None, :, None, None]
        return self._score([constant.expand_as(batch.targets) for batch in self.batches])

    def _score(self, outputs: list[torch.Tensor]) -> dict[str, Any]:
        picked = [(out.permute(0, 2, 3, 1)[b.mask], b.targets.permute(0, 2, 3, 1)[b.mask])
                  for out, b in zip(outputs, self.batches)]
        predicted, wanted = (torch.cat(part) for part in zip(*picked))
        mae = (from_network(predicted) - torch.expm1(wanted)).abs().mean(dim=0)
        return {"val_loss": float((predicted - wanted).abs().mean()),
                "val_mae": {name: float(v) for name, v in zip(TARGETS, mae)}}


def _validation(shards: Sequence[Shard], train_shards: Sequence[Shard], config: TrainConfig) -> _Validation:
    sampler = CropSampler(shards, config.crop)
    rng = np.random.default_rng([config.seed, 1 << 20])  # apart from every epoch's (seed, epoch)
    sizes = [min(config.batch_size, config.val_crops - start) for start in range(0, config.val_crops, config.batch_size)]
    median = np.median(np.concatenate([s.targets for s in train_shards]), axis=0)
    return _Validation([sampler.batch(rng, size, augment=False) for size in sizes], torch.as_tensor(median))


def resolve_device(name: str) -> torch.device:
    """'auto' -> CUDA when available, else the CPU; anything else as torch reads it."""
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def train(data_dir: Path, out_dir: Path, config: TrainConfig, progress: Progress | None = None) -> TrainResult:
    """Train (or go on training) the UNet on the shards in ``data_dir``; results in ``out_dir``.

    ``progress`` receives dicts with an ``event`` key: "start" (or "resume", with the epochs
    already done), "step" (epoch, step, steps, loss), "epoch" (the history line), "time-limit",
    and "done". Raises ValueError when ``out_dir`` holds a checkpoint of a different configuration
    or split, rather than silently mixing two runs.
    """
    report = progress if progress is not None else (lambda event: None)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    train_paths, val_paths = split_homes(shards.shard_paths(data_dir), config.val_fraction, config.seed)
    homes = {"train": [p.stem for p in train_paths], "val": [p.stem for p in val_paths]}
    threads = torch.get_num_threads()
    if config.threads:
        torch.set_num_threads(config.threads)
    try:
        return _Run(config, out_dir, homes, report).fit(train_paths, val_paths)
    finally:
        torch.set_num_threads(threads)


class _Run:
    """One invocation of `train`: the model, its optimiser and the run's files."""

    def __init__(self, config: TrainConfig, out_dir: Path, homes: dict[str, list[str]], report: Progress) -> None:
        self.config, self.out_dir, self.homes, self.report = config, out_dir, homes, report
        self.device = resolve_device(config.device)
        torch.manual_seed(config.seed)
        self.model = FrontierUNet(config.model).to(self.device)
        self.optimizer = torch.optim.Adam(self.model.parameters(), lr=config.lr)
        self.history: list[dict[str, Any]] = []
        self.checkpoint_path = out_dir / "checkpoint.pt"
        self.model_path = out_dir / "model.pt"

    def fit(self, train_paths: list[Path], val_paths: list[Path]) -> TrainResult:
        deadline = math.inf if self.config.max_minutes is None else time.monotonic() + 60 * self.config.max_minutes
        resumed_after = self._resume()
        self.report({"event": "resume" if resumed_after else "start", "epochs_done": resumed_after,
                     "epochs": self.config.epochs, "device": str(self.device),
                     "train_homes": len(self.homes["train"]), "val_homes": len(self.homes["val"])})
        resolution = self.config.model.model_resolution
        train_shards = [load_shard(p, resolution) for p in train_paths]
        sampler = CropSampler(train_shards, self.config.crop)
        validation = _validation([load_shard(p, resolution) for p in val_paths], train_shards, self.config)
        baseline = validation.baseline()
        stopped_early = False
        for epoch in range(resumed_after + 1, self.config.epochs + 1):
            # every invocation trains at least one step, or a short limit would never get anywhere
            if epoch > resumed_after + 1 and time.monotonic() > deadline:
                stopped_early = True
                break
            line = self._epoch(epoch, sampler, validation, deadline)
            line["baseline_val_loss"] = baseline["val_loss"]
            self._finish_epoch(line, baseline)
            if line["cut_short"]:
                stopped_early = True
                break
        if stopped_early:
            self.report({"event": "time-limit", "epochs_done": self.history[-1]["epoch"],
                         "max_minutes": self.config.max_minutes})
        best = min(self.history, key=lambda line: line["val_loss"])["epoch"]
        result = TrainResult(self.model_path, list(self.history), best, baseline, resumed_after, stopped_early)
        self.report({"event": "done", "best_epoch": best, "stopped_early": stopped_early, "baseline": baseline})
        return result

    def _epoch(self, epoch: int, sampler: CropSampler, validation: _Validation, deadline: float) -> dict[str, Any]:
        """Train one epoch (fewer steps if the deadline comes first) and validate it: its history line."""
        started = time.monotonic()
        lr = self.config.lr_at(epoch)
        for group in self.optimizer.param_groups:
            group["lr"] = lr
        rng = np.random.default_rng([self.config.seed, epoch])
        self.model.train()
        losses = []
        for step in range(1, self.config.steps_per_epoch + 1):
            batch = sampler.batch(rng, self.config.batch_size, augment=True).to(self.device)
            loss = masked_l1(self.model(batch.inputs), batch.targets, batch.mask)
            self.optimizer.zero_grad(set_to_none=True)
            loss.backward()
            self.optimizer.step()
            losses.append(loss.item())
            self.report({"event": "step", "epoch": epoch, "step": step, "steps": self.config.steps_per_epoch,
                         "loss": losses[-1]})
            if time.monotonic() > deadline:
                break
        scores = validation.evaluate(self.model, self.device)
        return {"epoch": epoch, "steps": len(losses), "cut_short": len(losses) < self.config.steps_per_epoch,
                "train_loss": float(np.mean(losses)), **scores, "lr": lr,
                "seconds": round(time.monotonic() - started, 2)}

    def _finish_epoch(self, line: dict[str, Any], baseline: dict[str, Any]) -> None:
        """Keep the epoch: the best model if it is one, the checkpoint, then history and plot."""
        self.history.append(line)
        if line["val_loss"] <= min(h["val_loss"] for h in self.history):
            self._save_model(line, baseline)
        atomic_save({"format": CHECKPOINT_FORMAT, "config": self.config.outcome_fields(), "homes": self.homes,
                     "history": self.history, "model": self.model.state_dict(),
                     "optimizer": self.optimizer.state_dict()}, self.checkpoint_path)
        with (self.out_dir / "history.jsonl").open("a") as history:
            history.write(json.dumps(line) + "\n")
        plot_history(self.history, self.out_dir / "loss.png")
        self.report({"event": "epoch", **line})

    def _save_model(self, line: dict[str, Any], baseline: dict[str, Any]) -> None:
        """Write the current weights as ``model.pt``, with how they did on epoch ``line``."""
        metadata = {"epoch": line["epoch"], "train_loss": line["train_loss"], "val_loss": line["val_loss"],
                    "val_mae": line["val_mae"], "baseline": baseline, "homes": self.homes,
                    "train_config": self.config.to_dict()}
        save_model(self.model_path, self.model, self.config.model, metadata)

    def _resume(self) -> int:
        """Load the checkpoint of an earlier invocation, if any: the number of epochs it finished.

        The history file is rewritten from the checkpoint, which is saved first: an invocation
        stopped between the two leaves no epoch in the history that the checkpoint lacks.
        """
        if not self.checkpoint_path.exists():
            (self.out_dir / "history.jsonl").unlink(missing_ok=True)
            return 0
        state = load_plain(self.checkpoint_path)
        if state.get("format") != CHECKPOINT_FORMAT:
            raise ModelFileError(f"{self.checkpoint_path}: not a {CHECKPOINT_FORMAT} checkpoint")
        for key, mine in (("config", self.config.outcome_fields()), ("homes", self.homes)):
            if state.get(key) != mine:
                raise ValueError(f"{self.checkpoint_path} was written with other {key}: "
                                 "use another output directory, or delete it to start over")
        self.model.load_state_dict(state["model"])
        self.optimizer.load_state_dict(state["optimizer"])
        self.history = list(state["history"])
        (self.out_dir / "history.jsonl").write_text("".join(json.dumps(line) + "\n" for line in self.history))
        return int(self.history[-1]["epoch"]) if self.history else 0


def read_history(path: Path) -> list[dict[str, Any]]:
    """The epochs of a ``history.jsonl``, in order."""
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def plot_history(history: Sequence[dict[str, Any]], path: Path) -> None:
    """Training and validation loss per epoch, with the median baseline as a dashed line."""
    epochs = [line["epoch"] for line in history]
    figure = Figure(figsize=(6, 4))  # no pyplot: no global backend, nothing left open
    axes = figure.subplots()
    axes.plot(epochs, [line["train_loss"] for line in history], "o-", label="training")
    axes.plot(epochs, [line["val_loss"] for line in history], "s-", label="validation")
    if history:
        axes.axhline(history[-1]["baseline_val_loss"], color="grey", linestyle="--",
                     label="validation, training median")
    axes.set_xlabel("epoch")
    axes.xaxis.set_major_locator(MaxNLocator(integer=True))
    axes.set_ylabel("L1 loss on frontier pixels (log1p units)")
    axes.set_title("Frontier-property UNet")
    axes.legend()
    figure.tight_layout()
    figure.savefig(path, dpi=100)

