"""Independent calls run one after another, side by side in worker processes, or as Ray tasks.

Evaluations and data generation hand out whole episodes or homes, each a few seconds to minutes of
CPU; results are wanted as each finishes, so that they can be appended and shown at once. `as_finished`
is the one place that hands them out: here, to spawned processes (`in_processes`), or to a Ray
cluster (`agent.app.runtime.ray_backend`, with ``--ray``). Workers are spawned, never forked: the
caller may hold threads, Zenoh sessions or PyBullet clients that a fork would copy in a broken state.

Ctrl-C is the caller's to handle: workers ignore SIGINT (they are spawned with it blocked, so one
that comes while they start and import waits until `quiet_worker` ignores it), and on it the caller
cancels the calls not yet started and ends the running ones (SIGTERM, which a worker turns into
SystemExit so that its cleanup, a world child's shutdown included, runs; SIGKILL for one that does
not end within a few seconds), keeping what finished. A caller killed from outside signals no
worker: each worker ends itself once its parent is gone.
"""

from __future__ import annotations

import atexit
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from typing import Any, TypeVar

Result = TypeVar("Result")


def as_finished(function: Callable[..., Result], calls: Sequence[tuple[Any, ...]], workers: int,
                ray: str | None = None, cpus: float = 1.0) -> Iterator[tuple[tuple[Any, ...], Result]]:
    """(arguments, ``function(*arguments)``) for each of ``calls``, as each finishes.

    With ``ray``, each call is a Ray task (`agent.app.runtime.ray_backend`). Otherwise, with one
    worker (or one call) they run here, in order, and else in up to ``workers`` spawned processes
    (`in_processes`). Either way ``function`` and its arguments must be importable and picklable,
    and the calls not finished are cancelled when the caller stops early (close the iterator, as
    `contextlib.closing` does, so that this happens at once).

    Args:
        function: what each call runs.
        calls: each call's arguments.
        workers: processes at most; with ``ray``, the size of a cluster started here.
        ray: None for processes here; `ray_backend.LOCAL` to start a Ray cluster here, or the
            address of one to join.
        cpus: the CPUs each call uses, which a Ray task declares.

    Yields:
        Each call's arguments and result.

    Raises:
        ValueError: fewer than one worker.
        agent.app.runtime.ray_backend.RayError: Ray is missing, or its cluster cannot be had.
    """
    if workers < 1:
        raise ValueError(f"workers: {workers} must be at least 1")
    if ray is not None:
        from agent.app.runtime import ray_backend

        yield from ray_backend.as_finished(function, calls, ray, cpus, workers)
    elif workers == 1 or len(calls) <= 1:
        for arguments in calls:
            yield arguments, function(*arguments)
    else:
        yield from in_processes(function, calls, workers)


def in_processes(function: Callable[..., Result], calls: Sequence[tuple[Any, ...]], workers: int,
                 initializer: Callable[..., None] | None = None, initargs: tuple[Any, ...] = ()
                 ) -> Iterator[tuple[tuple[Any, ...], Result]]:
    """(arguments, ``function(*arguments)``) for each of ``calls``, run in up to ``workers`` spawned
    processes, as each finishes; on Ctrl-C, or once the caller stops early, the calls not started
    are cancelled and the running ones ended (`stop_workers`).

    Args:
        function: what each call runs.
        calls: each call's arguments.
        workers: processes at most.
        initializer: what each process runs first, `quiet_worker` when None; another must call it.
        initargs: its arguments.

    Yields:
        Each call's arguments and result.
    """
    if not calls:
        return
    pool = ProcessPoolExecutor(min(workers, len(calls)), mp_context=multiprocessing.get_context("spawn"),
                               initializer=initializer or quiet_worker, initargs=initargs)
    finished = False
    try:
        with sigint_held():
            pending = {pool.submit(function, *arguments): arguments for arguments in calls}
        while pending:
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                yield pending.pop(future), future.result()
        finished = True
    finally:
        if finished:
            pool.shutdown(wait=True)
        else:  # Ctrl-C, a call that raised, or a caller that asks for no more
            stop_workers(pool)


def quiet_worker() -> None:
    """Worker initialiser: leave Ctrl-C (SIGINT) to the parent; on SIGTERM run the exit handlers (a
    world child's shutdown among them) and end the process. Not by SystemExit: the pool's worker
    loop catches that as the call's error and would go on serving. A worker whose parent has ended
    ends too (`_end_with_parent`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # spawned with it blocked: `sigint_held`
    signal.signal(signal.SIGTERM, _end_worker)
    threading.Thread(target=_end_with_parent, args=(os.getppid(),), name="end-with-parent", daemon=True).start()


def _end_with_parent(parent: int, period_s: float = 0.5) -> None:
    """End this worker (as SIGTERM does) once its parent is no longer ``parent``: a pool's caller
    killed from outside (``kill``, a scheduler, the machine short of memory) signals none of its
    workers, and they went on with their calls and then waited for more, each holding its memory
    and its world, for as long as the machine ran."""
    while True:
        time.sleep(period_s)
        if os.getppid() != parent:
            _end_worker()


@contextmanager
def sigint_held() -> Iterator[None]:
    """Block SIGINT in this thread while a pool spawns its workers (they spawn on submit): a
    worker inherits the block, so a Ctrl-C that comes while it starts and imports waits until
    `quiet_worker` ignores it, instead of raising KeyboardInterrupt in the middle of an import and
    printing its traceback. Here the signal comes when the block lifts, or at once through
    another thread of this process."""
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def _end_worker(*_: object) -> None:
    """SIGTERM in a worker: its exit handlers, then exit at once."""
    atexit._run_exitfuncs()
    os._exit(128 + signal.SIGTERM)


def stop_workers(pool: ProcessPoolExecutor, grace_s: float = 5.0) -> None:
    """After Ctrl-C (or a call that raised, or a caller that wants no more): cancel the calls not yet
    started and end the running ones: SIGTERM, and SIGKILL for a worker still there after
    ``grace_s`` (one blocked in a call that never returns to Python, a query to a world the same
    Ctrl-C ended, would otherwise hold the pool's shutdown forever).

    Args:
        pool: a pool whose workers ran `quiet_worker`.
        grace_s: how long the workers have to clean up.
    """
    # the executor offers no other way to end a call; read them first: shutdown forgets them
    processes = list((pool._processes or {}).values())
    manager = pool._executor_manager_thread
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        process.terminate()
    deadline = time.monotonic() + grace_s
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
    if manager is not None:
        # The pool's manager thread closes its wake-up pipe once it sees its workers gone. Let it
        # finish: the executor's exit hook writes to that pipe unlocked, and if it runs while the
        # thread closes it, the command's exit after Ctrl-C prints "Bad file descriptor".
        manager.join(grace_s)
