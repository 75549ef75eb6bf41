"""Training the frontier-property UNet on shards of explored homes.

The data are one ``home-NNNNN.npz`` per home (`agent.lfe.shards`, made by `agent.lfe.samples`): the encoded maps of
the snapshots taken while a robot explored it, and the frontier pixels of each snapshot with
their ground-truth R_A, D_in and D_out. Training follows the paper (§VI): Adam at 1e-3, divided
by ten every two epochs, six epochs, an L1 loss on the frontier pixels only.

What differs is the budget: a few thousand snapshots and half an hour on a laptop CPU instead of
220,000 tuples and twelve GPU hours. So each step sees a batch of crops of the map around
frontier pixels, turned and mirrored at random (`agent.lfe.training_set`), and an epoch is a
fixed number of steps rather than a pass over the data.

Homes, not snapshots, are held out for validation (`agent.lfe.training_set.split_homes`).
Validation runs on a fixed set of crops of the held-out homes, next to a baseline that predicts
the training median everywhere (`agent.lfe.validation`).

A run writes into ``out_dir``: ``model.pt`` (the best epoch by validation loss), ``history.jsonl``
(one line per finished epoch), ``loss.png`` and ``checkpoint.pt``. Running the same command again
continues after the last finished epoch; each epoch draws its crops from a generator seeded by
(seed, epoch), so a resumed run ends with the same weights as one that never stopped (on CPU).
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import torch
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from agent.lfe import shards
from agent.lfe.model import FrontierUNet, ModelFileError, UNetConfig, atomic_save, load_plain, save_model
from agent.lfe.training_set import CropSampler, Shard, load_shard, split_homes
from agent.lfe.validation import Validation, masked_l1

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

    Args:
        model: the network's shape.
        epochs: epochs in all, those of earlier invocations included.
        lr: Adam's learning rate in the first epochs.
        lr_decay: the factor the learning rate is multiplied by every ``lr_decay_every`` epochs.
        lr_decay_every: epochs between decays.
        batch_size: crops per optimiser step.
        crop: the side of a crop in pixels, a multiple of ``model.multiple``.
        steps_per_epoch: optimiser steps per epoch.
        val_fraction: the share of homes held out for validation.
        val_crops: crops of the held-out homes scored after each epoch.
        seed: the split, the initialisation and the crops.
        max_minutes: the time limit of one invocation; None for none.
        device: "auto", or a torch device such as "cpu" or "cuda".
        threads: torch's CPU threads; 0 leaves torch's own choice.

    Raises:
        ValueError: a field out of its range, a crop the UNet's poolings do not divide, or an
            unknown device.
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
        """The learning rate of an epoch, as the paper's schedule has it.

        Args:
            epoch: the epoch, from 1.

        Returns:
            ``lr``, times ``lr_decay`` after every ``lr_decay_every`` epochs.
        """
        return self.lr * self.lr_decay ** ((epoch - 1) // self.lr_decay_every)

    def to_dict(self) -> dict[str, Any]:
        """The configuration as plain data, for the model file's metadata.

        Returns:
            Every field, the model's shape as a nested dict.
        """
        return asdict(self)

    def outcome_fields(self) -> dict[str, Any]:
        """The fields that decide the weights of each epoch: a resumed run must agree on all of them.

        ``epochs`` is not one of them, so a finished run can be extended by asking for more.

        Returns:
            `to_dict` less ``epochs``, ``max_minutes``, ``device`` and ``threads``.
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
    """What a call to `train` left behind and how good it is.

    Args:
        model_path: the best epoch's weights.
        history: every finished epoch, resumed ones included.
        best_epoch: the epoch with the lowest validation loss.
        baseline: the training median's validation loss and MAE per channel.
        resumed_after: epochs finished before this call (0: a fresh start).
        stopped_early: the time limit cut this call short; run again to continue.
    """

    model_path: Path
    history: list[dict[str, Any]]
    best_epoch: int
    baseline: dict[str, Any]
    resumed_after: int
    stopped_early: bool


def _validation(shards: Sequence[Shard], train_shards: Sequence[Shard], config: TrainConfig) -> Validation:
    """The run's fixed validation crops of the held-out homes, and the training median for the baseline."""
    sampler = CropSampler(shards, config.crop)
    rng = np.random.default_rng([config.seed, 1 << 20])  # apart from every epoch's (seed, epoch)
    sizes = [min(config.batch_size, config.val_crops - start) for start in range(0, config.val_crops, config.batch_size)]
    median = np.median(np.concatenate([s.targets for s in train_shards]), axis=0)
    return Validation([sampler.batch(rng, size, augment=False) for size in sizes], torch.as_tensor(median))


def resolve_device(name: str) -> torch.device:
    """The torch device a configuration names.

    Args:
        name: "auto", or a torch device such as "cpu" or "cuda".

    Returns:
        For "auto" CUDA when available, else the CPU; anything else as torch reads it.
    """
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)


def train(data_dir: Path, out_dir: Path, config: TrainConfig, progress: Progress | None = None) -> TrainResult:
    """Train (or go on training) the UNet on the shards in ``data_dir``; results in ``out_dir``.

    Args:
        data_dir: the shards (`agent.lfe.shards`).
        out_dir: ``model.pt``, ``history.jsonl``, ``loss.png`` and ``checkpoint.pt`` go here.
        config: how to train.
        progress: receives dicts with an ``event`` key: "start" (or "resume", with the epochs
            already done), "step" (epoch, step, steps, loss), "epoch" (the history line),
            "time-limit", and "done".

    Returns:
        The model's path, the history and the best epoch.

    Raises:
        ValueError: ``out_dir`` holds a checkpoint of a different configuration or split (rather
            than silently mixing two runs), or fewer than two homes.
        ModelFileError: ``out_dir`` holds a checkpoint file of another kind.
        FileNotFoundError: ``data_dir`` holds no shards.
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

    def _epoch(self, epoch: int, sampler: CropSampler, validation: Validation, deadline: float) -> dict[str, Any]:
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
    """Read a run's history file.

    Args:
        path: a ``history.jsonl``.

    Returns:
        The epochs' lines, in order.
    """
    return [json.loads(line) for line in Path(path).read_text().splitlines() if line.strip()]


def plot_history(history: Sequence[dict[str, Any]], path: Path) -> None:
    """Draw the training and validation loss per epoch, with the median baseline as a dashed line.

    Args:
        history: the epochs' lines (`read_history`).
        path: the image file to write.
    """
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

