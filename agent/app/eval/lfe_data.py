"""`homebot lfe data`: the frontier-property network's training data, many homes side by side.

Each home's samples come from `agent.lfe.samples.home_samples`; here the homes are handed out to
worker processes or Ray tasks (`agent.app.runtime.pool`) and each home's arrays are written as one shard
(`agent.lfe.shards`) as soon as it finishes. Shards are written whole (a temporary file, then a
rename), so a run that is stopped leaves no half shard, and a rerun skips the homes whose shard
is there.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path

from agent.app.runtime.pool import as_finished
from agent.lfe.samples import DataConfig, home_samples
from agent.lfe.shards import shard_path, write_shard


@dataclass(frozen=True)
class DatasetSummary:
    """What one `generate_dataset` call did.

    Args:
        out_dir: the shard folder.
        written: seeds whose shard this call wrote, in the order they finished.
        skipped: seeds whose shard was there already.
        snapshots: maps in the shards written.
        pixels: frontier pixels in them.
        seconds: how long the call took.
    """

    out_dir: Path
    written: tuple[int, ...]
    skipped: tuple[int, ...]
    snapshots: int
    pixels: int
    seconds: float

    def __str__(self) -> str:
        return (f"{self.out_dir}: {len(self.written)} homes written ({self.snapshots} maps, {self.pixels} frontier "
                f"pixels), {len(self.skipped)} already there, {self.seconds:.0f} s")


def generate_dataset(out_dir: Path, seeds: Sequence[int], config: DataConfig = DataConfig(), workers: int = 1,
                     progress: Callable[[int, int, int | None], None] | None = None,
                     ray: str | None = None) -> DatasetSummary:
    """Write one shard per seed into ``out_dir``, skipping the seeds whose shard is there.

    With ``workers`` > 1, homes are explored in that many processes and each shard is written as
    its home finishes; if one home fails, the shards already written stay, so a rerun picks up
    where this one stopped.

    Args:
        out_dir: the shard folder, made if missing.
        seeds: the homes' seeds; repeats are made once.
        config: how each home's samples are made.
        workers: homes explored at once, one process each.
        progress: called as ``progress(done, total, samples)`` once per home, skipped ones first,
            with the maps this call recorded in it (None for a skipped home, so that an estimate
            of the time left can leave those out).
        ray: explore each home as a Ray task of one CPU (`agent.app.runtime.pool.as_finished`),
            its arrays coming back to be written here: `ray_backend.LOCAL` or a cluster's address;
            None: in worker processes here.

    Returns:
        What was written and skipped.

    Raises:
        ValueError: ``workers`` not a positive integer, or a negative seed.
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
    with closing(as_finished(home_samples, [(seed, config) for seed in todo], workers, ray)) as homes:
        for (seed, _), arrays in homes:
            write_shard(shard_path(out_dir, seed), arrays)
            written.append(seed)
            snapshots += len(arrays["maps"])
            pixels += len(arrays["pixels"])
            done += 1
            if progress is not None:
                progress(done, len(unique), len(arrays["maps"]))
    return DatasetSummary(out_dir, tuple(written), tuple(skipped), snapshots, pixels, time.monotonic() - started)
