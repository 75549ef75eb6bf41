"""The `homebot lfe` commands: make training data for the frontier-property network and train it.

- ``lfe data --homes N`` explores N seeded homes with plain frontier exploration and writes one
  shard of labelled partial maps per home (`agent.app.eval.lfe_data`); a rerun skips the homes done.
- ``lfe train`` fits the UNet on those shards with a held-out split by home (`agent.lfe.train`),
  writing the model, its per-epoch history and the loss curves; a rerun resumes after the last
  finished epoch.

`main(argv)` takes the words after ``lfe`` and returns the exit code: 0 done, 2 bad arguments.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from pathlib import Path

from agent.app.cli.options import add_ray_option, count_option, seed_option
from agent.app.progress import ProgressLine
from agent.app.runtime import interrupt

DEFAULT_DATA = Path("runs/lfe-data")
DEFAULT_TRAIN = Path("runs/lfe-train")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="homebot lfe", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    data = commands.add_parser("data", help="labelled partial maps from seeded homes, one shard per home")
    data.add_argument("--homes", type=count_option, required=True, help="how many homes (seeds FIRST .. FIRST+N-1)")
    data.add_argument("--first-seed", type=seed_option, default=0, help="seed of the first home (default 0)")
    data.add_argument("--out", type=Path, default=DEFAULT_DATA, help=f"shard folder (default {DEFAULT_DATA})")
    data.add_argument("--workers", type=count_option, default=1, help="homes explored at once, one process each")
    add_ray_option(data, "home")
    train = commands.add_parser("train", help="fit the UNet on the shards; held-out split by home")
    train.add_argument("--data", type=Path, default=DEFAULT_DATA, help=f"shard folder (default {DEFAULT_DATA})")
    train.add_argument("--out", type=Path, default=DEFAULT_TRAIN,
                       help=f"model.pt, history.jsonl and loss.png go here (default {DEFAULT_TRAIN})")
    train.add_argument("--epochs", type=count_option, help="epochs (default 6, the paper's)")
    train.add_argument("--minutes", type=float, help="stop after this long, keeping the best model so far")
    train.add_argument("--device", help="cpu, cuda or auto (default auto: a GPU when there is one)")
    train.add_argument("--seed", type=seed_option, help="split, initialisation and crops (default 0)")
    train.add_argument("--steps-per-epoch", type=count_option, help="optimiser steps per epoch (default 120)")
    train.add_argument("--batch-size", type=count_option, help="crops per step (default 16)")
    train.add_argument("--crop", type=count_option, help="side of a training crop in cells (default 128)")
    return parser


def main(argv: list[str] | None = None) -> int:
    """``homebot lfe``: make the training data (``data``) or train the network (``train``).

    Args:
        argv: the command line's arguments (``sys.argv[1:]`` when None).

    Returns:
        The exit status: 0 on success.
    """
    try:
        args = _parser().parse_args(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)
    from agent.app.runtime.ray_backend import RayError

    try:
        return _data(args) if args.command == "data" else _train(args)
    except (ValueError, FileNotFoundError, RayError) as error:
        print(f"homebot lfe {args.command}: {error}", file=sys.stderr)
        return 2


def _data(args: argparse.Namespace) -> int:
    from agent.app.eval.lfe_data import generate_dataset

    if args.homes < 1:
        raise ValueError(f"--homes: {args.homes} must be at least 1")
    if args.first_seed < 0:
        raise ValueError(f"--first-seed: {args.first_seed} must not be negative")
    if args.workers < 1:
        raise ValueError(f"--workers: {args.workers} must be at least 1")
    started = time.monotonic()
    explored = 0
    line = ProgressLine()

    def progress(done: int, total: int, samples: int | None) -> None:
        nonlocal explored
        if samples is None:
            line.show(f"{done}/{total} homes (already there)", done == total)
        else:
            explored += 1
            rate = (time.monotonic() - started) / explored
            line.show(f"{done}/{total} homes, last one {samples} maps, ~{rate * (total - done) / 60:.0f} min left",
                      done == total)
        interrupt.check()

    seeds = range(args.first_seed, args.first_seed + args.homes)
    summary = generate_dataset(args.out, seeds, workers=args.workers, progress=progress, ray=args.ray)
    print(summary)
    return 0


def _train(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from agent.lfe.train import TrainConfig, train

    overrides = {"epochs": args.epochs, "max_minutes": args.minutes, "device": args.device, "seed": args.seed,
                 "steps_per_epoch": args.steps_per_epoch, "batch_size": args.batch_size, "crop": args.crop}
    config = replace(TrainConfig(), **{k: v for k, v in overrides.items() if v is not None})

    result = train(args.data, args.out, config, training_progress())
    best = next((line for line in result.history if line["epoch"] == result.best_epoch), None)
    if best is not None:
        mae = ", ".join(f"{value:.2f}" for value in best["val_mae"].values())
        print(f"best epoch {result.best_epoch}: validation L1 {best['val_loss']:.3f} "
              f"(median baseline {result.baseline['val_loss']:.3f}); MAE R_A, D_in, D_out {mae}")
    print(f"model {result.model_path}, curves {args.out / 'loss.png'}")
    print(f"to ship it with the package: cp {args.out / 'model.pt'} agent/data/lfe-unet.pt")
    return 0


def training_progress() -> Callable[[dict], None]:
    """The training's progress on stderr: one line per epoch and for the start and the end, the
    steps of an epoch on a progress line (`agent.app.progress`).

    Returns:
        A ``progress`` callback for `agent.lfe.train.train`.
    """
    line = ProgressLine()

    def progress(event: dict) -> None:
        interrupt.check()
        kind = event["event"]
        if kind == "step":
            line.show(f"epoch {event['epoch']}: step {event['step']}/{event['steps']}, loss {event['loss']:.3f}")
        elif kind == "epoch":
            line.show(f"epoch {event['epoch']}: training L1 {event['train_loss']:.3f}, validation L1 "
                      f"{event['val_loss']:.3f} (baseline {event['baseline_val_loss']:.3f}), "
                      f"lr {event['lr']:g}, {event['seconds']:.0f} s", last=True)
        else:
            _training_event(event)

    return progress


def _training_event(event: dict) -> None:
    """A line for the training's start, its resumption or its time limit."""
    kind = event["event"]
    if kind in ("start", "resume"):
        after = f", resuming after epoch {event['epochs_done']}" if kind == "resume" else ""
        sys.stderr.write(f"  training on {event['train_homes']} homes, validating on {event['val_homes']}, "
                         f"{event['epochs']} epochs on {event['device']}{after}\n")
    elif kind == "time-limit":
        sys.stderr.write(f"  stopped at the {event['max_minutes']:g}-minute limit after epoch {event['epochs_done']}; "
                         "run the same command again to go on\n")
    sys.stderr.flush()
