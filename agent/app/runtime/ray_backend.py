"""Independent calls run as Ray tasks, on a local Ray cluster started here or on one joined.

Ray is an optional extra (``pip install 'homebot[ray]'``), imported only when ``--ray`` is given.
Each call is one task that declares the CPUs it uses, so that Ray runs no more of them on a node
than it has room for, and that Ray runs again, up to `MAX_RETRIES` times, when the worker process
or the node running it dies (an exception the call raises is not retried: it is the call's
result). The caller gets each result as it finishes; once it stops early (Ctrl-C, an error, or
simply not asking for more) a cluster started here is shut down, its workers with it, and on a
cluster joined the tasks not finished are cancelled and their workers killed, so that nothing is
left running.

The function and its arguments travel by reference and by pickle: each node must have the same
homebot installed (docs/scale.md), and a task that needs a file (a model, a Zenoh configuration)
finds it at the same path on every node.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from types import ModuleType
from typing import Any, TypeVar

Result = TypeVar("Result")

#: ``--ray`` without an address: start a local cluster for this command alone.
LOCAL = "local"
#: What ``--ray`` says when Ray is not installed.
NEEDS_RAY = "--ray needs the ray package: pip install 'homebot[ray]'"
#: How often Ray runs a task again whose worker or node died, before the command fails with it.
MAX_RETRIES = 3
#: How long the caller waits for a result before it looks again: a Ctrl-C is felt within this at the latest.
WAIT_S = 0.5


class RayError(RuntimeError):
    """Ray is not installed, the cluster cannot be started or joined, or a task's worker or node died
    each time it ran; the text says which."""


def ray_module() -> ModuleType:
    """The ray package, imported.

    Returns:
        The module.

    Raises:
        RayError: it is not installed, with how to install it.
    """
    try:
        import ray
    except ImportError:
        raise RayError(NEEDS_RAY) from None
    return ray


def as_finished(function: Callable[..., Result], calls: Sequence[tuple[Any, ...]], address: str, cpus: float,
                workers: int, slots: Sequence[Any] | None = None) -> Iterator[tuple[tuple[Any, ...], Result]]:
    """(arguments, ``function(*arguments)``) for each of ``calls``, each run as a Ray task, as each finishes.

    Args:
        function: what each call runs: a module-level function of an installed module.
        calls: each call's arguments (picklable).
        address: `LOCAL` to start a cluster here, else the address of one to join (``auto``,
            ``HOST:6379``); a cluster this process has joined already is used as it is.
        cpus: the CPUs each task declares (a fraction is allowed).
        workers: tasks at once on a cluster started here, which gets ``workers × cpus`` CPUs; a
            joined cluster runs as many at once as its CPUs hold.
        slots: things only one call may use at a time (running worlds to join): each call gets a
            free one as its last argument, held until its task has finished, so no more calls run
            at once than there are slots. None: every call is handed out at once.

    Yields:
        Each call's arguments (a slot left out) and result.

    Raises:
        RayError: Ray is missing, the cluster cannot be started or joined, or a task's worker or
            node died more than `MAX_RETRIES` times.
        ray.exceptions.RayTaskError: a call raised; its exception is the cause.
        ValueError: an empty list of slots (no call could ever run).
    """
    if slots is not None and not slots:
        raise ValueError("slots: none given, so no call could run")
    with cluster(address, math.ceil(workers * cpus)) as (ray, started_here):
        remote = ray.remote(function).options(num_cpus=cpus, max_retries=MAX_RETRIES, retry_exceptions=False)
        waiting, free = list(calls), list(slots) if slots is not None else None
        pending: dict[Any, tuple[tuple[Any, ...], Any]] = {}
        try:
            while waiting or pending:
                while waiting and (free is None or free):
                    arguments, slot = waiting.pop(0), free.pop(0) if free else None
                    pending[remote.remote(*arguments, *([slot] if free is not None else []))] = (arguments, slot)
                ready, _ = ray.wait(list(pending), num_returns=1, timeout=WAIT_S)
                for ref in ready:
                    arguments, slot = pending.pop(ref)
                    result = _result(ray, ref)
                    if free is not None:
                        free.append(slot)
                    yield arguments, result
        finally:
            # Stopped early: nothing goes on running for results no one will read. A cluster started
            # here ends with its shutdown; its tasks are not cancelled first, because Ray's driver
            # aborts when a forced cancel meets the reply of a task that just ended (its check "Tried
            # to complete task that was not pending"), as a Ctrl-C makes likely: the terminal's
            # SIGINT reaches this cluster's workers too, and ends their tasks at the same moment.
            if not started_here:
                for ref in pending:
                    ray.cancel(ref, force=True)


@contextmanager
def cluster(address: str, cpus: int) -> Iterator[tuple[ModuleType, bool]]:
    """In a Ray cluster: a local one of ``cpus`` CPUs started here (`LOCAL`), shut down at the end,
    or the one at ``address``, left at the end; a cluster this process is in already is used as
    it is, and left as it is.

    Its log lines stay in the cluster's session folder (``/tmp/ray/session_latest/logs`` on each
    node) rather than coming back between the command's progress lines.

    Args:
        address: `LOCAL`, or a cluster's address.
        cpus: the CPUs of a cluster started here.

    Yields:
        The ray module, connected, and whether the cluster was started here (and ends on leaving).

    Raises:
        RayError: Ray is missing, or the cluster cannot be started or joined.
    """
    ray = ray_module()
    if ray.is_initialized():
        yield ray, False
        return
    options: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False, "logging_level": logging.ERROR}
    try:
        if address == LOCAL:
            ray.init(address=LOCAL, num_cpus=max(1, cpus), **options)
        else:
            ray.init(address=address, **options)
    except Exception as error:  # Ray's own kinds vary: ConnectionError, OSError, RuntimeError, ValueError…
        where = ("a local Ray cluster could not be started" if address == LOCAL
                 else f"no Ray cluster joined at {address}")
        raise RayError(f"--ray: {where}: {error}") from None
    try:
        yield ray, address == LOCAL
    finally:
        ray.shutdown()


def _result(ray: ModuleType, ref: Any) -> Any:
    """A finished task's result; a task that died each time it ran is a RayError saying so."""
    try:
        return ray.get(ref)
    except ray.exceptions.RayTaskError:
        raise
    except ray.exceptions.RayError as error:
        raise RayError(f"--ray: a task ended without a result, its worker or node having died "
                       f"{MAX_RETRIES + 1} times: {error}") from None
