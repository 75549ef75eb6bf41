"""Independent calls run one after another, or side by side in worker processes.

Evaluations and data generation hand out whole episodes or homes, each a few seconds to minutes of
CPU; results are wanted as each finishes, so that they can be appended and shown at once. Workers
are spawned, never forked: the caller may hold threads, Zenoh sessions or PyBullet clients that a
fork would copy in a broken state.
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, TypeVar

Result = TypeVar("Result")


def as_finished(function: Callable[..., Result], calls: Sequence[tuple[Any, ...]], workers: int
                ) -> Iterator[tuple[tuple[Any, ...], Result]]:
    """(arguments, ``function(*arguments)``) for each of ``calls``, as each finishes.

    With one worker (or one call) they run here, in order; otherwise in up to ``workers`` spawned
    processes, so ``function`` and its arguments must be importable and picklable. Calls not yet
    started are cancelled when the caller stops early.

    Args:
        function: what each call runs.
        calls: each call's arguments.
        workers: processes at most.

    Yields:
        Each call's arguments and result.

    Raises:
        ValueError: fewer than one worker.
    """
    if workers < 1:
        raise ValueError(f"workers: {workers} must be at least 1")
    if workers == 1 or len(calls) <= 1:
        for arguments in calls:
            yield arguments, function(*arguments)
        return
    pool = ProcessPoolExecutor(min(workers, len(calls)), mp_context=multiprocessing.get_context("spawn"))
    try:
        pending = {pool.submit(function, *arguments): arguments for arguments in calls}
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in finished:
                yield pending.pop(future), future.result()
    finally:
        pool.shutdown(wait=True, cancel_futures=True)
