"""Independent calls run one after another, or side by side in worker processes.

Evaluations and data generation hand out whole episodes or homes, each a few seconds to minutes of
CPU; results are wanted as each finishes, so that they can be appended and shown at once. Workers
are spawned, never forked: the caller may hold threads, Zenoh sessions or PyBullet clients that a
fork would copy in a broken state.

Ctrl-C is the caller's to handle: workers ignore SIGINT, and on it the caller cancels the calls not
yet started and ends the running ones (SIGTERM, which a worker turns into SystemExit so that its
cleanup, a world child's shutdown included, runs), keeping what finished.
"""

from __future__ import annotations

import multiprocessing
import signal
import sys
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
    pool = ProcessPoolExecutor(min(workers, len(calls)), mp_context=multiprocessing.get_context("spawn"),
                               initializer=quiet_worker)
    try:
        pending = {pool.submit(function, *arguments): arguments for arguments in calls}
        while pending:
            finished, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in finished:
                yield pending.pop(future), future.result()
    except KeyboardInterrupt:
        stop_workers(pool)
        raise
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def quiet_worker() -> None:
    """Worker initialiser: leave Ctrl-C (SIGINT) to the parent; SIGTERM exits through SystemExit, cleanup run."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(128 + signal.SIGTERM))


def stop_workers(pool: ProcessPoolExecutor) -> None:
    """After Ctrl-C: cancel the calls not yet started and end the running ones (SIGTERM).

    Args:
        pool: a pool whose workers ran `quiet_worker`.
    """
    pool.shutdown(wait=False, cancel_futures=True)
    for process in list((pool._processes or {}).values()):  # the executor offers no other way to end a call
        process.terminate()
