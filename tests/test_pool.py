"""The process pool's early stop (`stop_workers`): calls still running are ended, and nothing of
the pool is left working when it returns, so the command's exit after Ctrl-C is quiet; and a pool
whose caller is killed from outside does not outlive it."""

from __future__ import annotations

import multiprocessing
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

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


#: A pool's caller: two workers in minute-long calls; it prints their process ids and waits.
CALLER = """
import multiprocessing, sys, time
sys.path.insert(0, {root!r})
from agent.app.runtime.pool import in_processes
results = in_processes(time.sleep, [(60.0,), (60.0,)], 2)
import threading
threading.Thread(target=lambda: next(results), daemon=True).start()
deadline = time.monotonic() + 60.0
while len(multiprocessing.active_children()) < 2 and time.monotonic() < deadline:
    time.sleep(0.1)
time.sleep(2.0)  # the workers have started their calls
print(" ".join(str(child.pid) for child in multiprocessing.active_children()), flush=True)
time.sleep(60)
"""


def test_the_workers_of_a_caller_killed_from_outside_end_too() -> None:
    root = str(Path(__file__).resolve().parents[1])
    caller = subprocess.Popen([sys.executable, "-c", CALLER.format(root=root)], stdout=subprocess.PIPE, text=True)
    assert caller.stdout is not None
    workers = [int(pid) for pid in caller.stdout.readline().split()]
    assert workers, "the caller started no workers"
    caller.send_signal(signal.SIGKILL)
    caller.wait()
    deadline = time.monotonic() + 10.0
    while any(Path(f"/proc/{pid}").exists() for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = [pid for pid in workers if Path(f"/proc/{pid}").exists()]
    for pid in left:  # not to leave them running after a failure
        os.kill(pid, signal.SIGKILL)
    assert not left, f"workers {left} outlived the caller"
