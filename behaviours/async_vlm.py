"""A behaviour that asks the VLM in a worker thread and stays RUNNING until the answer is in.

A remote model takes hundreds of milliseconds; the tick must not wait for it. `initialise` hands
the question to a one-thread executor (made in `setup`, shut down in `shutdown`), `update` polls
the future, fails with the reason on a timeout or an error, and passes the answer to `use` when it
arrives. The answer calls the ``wake`` the tree handed `setup`, if any, so the tree ticks again
as soon as it is in.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

import py_trees
from py_trees.common import Status

from agent.timing import StageTimer
from agent.vlm.protocol import VisionLanguageModel


class AsyncVLMQuery(py_trees.behaviour.Behaviour):
    """Base for leaves that ask the VLM: subclasses give `ask` (runs in the worker) and `use`.

    Args:
        name: the node's name.
        vlm: the model asked.
        timeout_s: how long an answer may take.
        timer: times the queries, if given.
    """

    stage = "vlm"

    def __init__(self, name: str, vlm: VisionLanguageModel, timeout_s: float, timer: StageTimer | None) -> None:
        super().__init__(name)
        self.vlm = vlm
        self.timeout_s = timeout_s
        self.timer = timer
        self._executor: ThreadPoolExecutor | None = None
        self._future: Future | None = None
        self._started = 0.0
        self._wake: Callable[[], None] | None = None

    def inputs(self) -> tuple[Any, ...]:
        """Read what the question needs from the blackboard (in the tick thread).

        Returns:
            The arguments `ask` is called with (none by default).
        """
        return ()

    def ask(self, *inputs: Any) -> Any:
        """Ask the VLM (in the worker thread); the result goes to `use`.

        Args:
            *inputs: what `inputs` read from the blackboard.

        Returns:
            The VLM's answer, handed to `use`.
        """
        raise NotImplementedError

    def use(self, answer: Any) -> Status:
        """Record the answer (in the tick thread) and say how it went.

        Args:
            answer: what `ask` returned.

        Returns:
            The behaviour's status for this tick.
        """
        raise NotImplementedError

    def setup(self, **kwargs: Any) -> None:
        """Make the executor the VLM is asked in; take the tree's ``wake``, if it hands one.

        Args:
            **kwargs: py_trees' setup arguments; ``wake`` is called once an answer is in.
        """
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="vlm")
        self._wake = kwargs.get("wake")

    def initialise(self) -> None:
        self._started = time.perf_counter()
        assert self._executor is not None, f"{self.name}.setup() makes the executor the VLM is asked in"
        self._future = self._executor.submit(self.ask, *self.inputs())
        if self._wake is not None:
            wake = self._wake
            self._future.add_done_callback(lambda _: wake())

    def update(self) -> Status:
        elapsed = time.perf_counter() - self._started
        if self._future is None:
            return Status.FAILURE
        if not self._future.done():
            if elapsed > self.timeout_s:
                self._future.cancel()
                self.feedback_message = f"the {self.vlm.name} VLM gave no answer within {self.timeout_s:.1f} s"
                return Status.FAILURE
            self.feedback_message = f"asking the {self.vlm.name} VLM ({elapsed:.1f} s)"
            return Status.RUNNING
        try:
            answer = self._future.result()
        except Exception as error:  # any backend failure ends the step with its reason
            self.feedback_message = f"the {self.vlm.name} VLM failed: {type(error).__name__}: {error}"
            return Status.FAILURE
        if self.timer is not None:
            self.timer.record(self.stage, elapsed * 1000.0)
        return self.use(answer)

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self._future is not None:
            self._future.cancel()
        self._future = None

    def shutdown(self) -> None:
        if self._executor is not None:
            self._executor.shutdown(wait=False, cancel_futures=True)
