"""The process pool's early stop (`stop_workers`): calls still running are ended, and nothing of
the pool is left working when it returns, so the command's exit after Ctrl-C is quiet."""

from __future__ import annotations

import multiprocessing
import time
from concurrent.futures import ProcessPoolExecutor

from agent.app.runtime.pool import in_processes, quiet_worker, stop_workers


def _running_pool(calls: int) -> ProcessPoolExecutor:
    """A spawned pool of ``calls`` workers, each in a call that would take a minute."""
    pool = ProcessPoolExecutor(calls, mp_context=multiprocessing.get_context("spawn"), initializer=quiet_worker)
    futures = [pool.submit(time.sleep, 60.0) for _ in range(calls)]
    deadline = time.monotonic() + 60.0
    while not all(future.running() for future in futures):
        assert time.monotonic() < deadline, "the calls never started"
        time.sleep(0.05)
    return pool


def test_stopping_a_pool_ends_its_workers_and_its_manager_thread() -> None:
    pool = _running_pool(2)
    processes, manager = list(pool._processes.values()), pool._executor_manager_thread
    stop_workers(pool, grace_s=5.0)
    assert not any(process.is_alive() for process in processes)
    # the interpreter's exit hook for pools writes to the pipe this thread closes as it ends: it must be done
    assert not manager.is_alive()


def test_a_caller_that_stops_early_gets_what_finished_and_no_more() -> None:
    results = in_processes(time.sleep, [(0.0,), (60.0,), (60.0,)], 2)
    started = time.monotonic()
    assert next(results) == ((0.0,), None)
    results.close()
    assert time.monotonic() - started < 50.0  # the minute-long calls were ended, not waited for
