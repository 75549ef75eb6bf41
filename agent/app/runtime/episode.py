"""Ticking a tree until the episode answers, fails, or runs out of time, and never hanging.

py_trees lets an exception inside a behaviour escape `tick()`. The runner catches it, names the
behaviour it came from, and ends the episode as a failure with that reason, so a bug in one leaf
is a recorded outcome rather than a crash.

Between ticks of a tree that is RUNNING the runner neither spins nor sleeps a fixed time: it waits
on its ``wake``, which it hands every behaviour as py_trees' ``setup(wake=...)`` argument. A leaf
that waits on something (a world command's reply, a VLM's answer, an arm's act in a worker) calls
it when that is in, and the tree ticks at once; the control calls it on a request. Without a
call, the tree ticks again after ``max_wait_s`` all the same (a leaf that waits on nothing that
calls it, the episode's time limit).
"""

from __future__ import annotations

import logging
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import py_trees
from py_trees.common import Status

from behaviours import blackboard as bb
from agent.app.runtime import interrupt
from agent.app.runtime.control import EpisodeControl, InjectedFault, instrument
from agent.app.runtime.snapshot import SnapshotEncoder

log = logging.getLogger(__name__)

SnapshotSink = Callable[[dict[str, Any]], None]


@dataclass
class EpisodeOutcome:
    """How an episode ended: answered (with the answer) or failed (with the reason)."""

    status: str  # "answered", "failed" or "interrupted" (SIGINT, Ctrl-C)
    reason: str
    answer: dict[str, Any] | None
    ticks: int
    seconds: float
    failed_behaviour: str | None = None
    extra: dict[str, Any] = field(default_factory=dict)


class EpisodeRunner:
    """Ticks an episode's tree until it answers, fails or runs out of time; a leaf's exception ends it as a failure.

    The control (`agent.app.runtime.control`) can pause the tree between ticks or before a
    behaviour, step it, and inject faults; the time spent paused counts neither against the
    wall-clock limit nor in the episode's seconds.

    Args:
        root: the tree (set up here, with ``wake`` handed to every behaviour's ``setup``).
        run_id: the run's id, in every snapshot.
        sinks: where the snapshots go (only those of ticks that changed what a viewer sees, and the
            first and last; see `agent.app.runtime.snapshot`).
        max_seconds: the episode's wall-clock limit.
        tick_period_s: the least time between ticks (0: a woken tree ticks at once).
        timer: times the stages, if given.
        control: pauses, steps and faults from outside (default: one nobody asks, which changes nothing).
        max_wait_s: the longest a RUNNING tree waits between ticks when nothing wakes it.
    """

    def __init__(self, root: py_trees.behaviour.Behaviour, run_id: str, sinks: list[SnapshotSink],
                 max_seconds: float, tick_period_s: float = 0.0,
                 timer: Any | None = None, control: EpisodeControl | None = None,
                 max_wait_s: float = 0.05) -> None:
        self.wake = threading.Event()  # set by a leaf whose reply is in, or by the control
        self.tree = py_trees.trees.BehaviourTree(root)
        self.tree.setup(wake=self.wake.set)  # the leaves make their executors and keep the wake
        self.visitor = py_trees.visitors.SnapshotVisitor()
        self.tree.visitors.append(self.visitor)
        self.run_id = run_id
        self.sinks = sinks
        self.max_seconds = max_seconds
        self.tick_period_s = tick_period_s
        self.max_wait_s = max_wait_s
        self.timer = timer
        self.blackboard = py_trees.blackboard.Client(name="EpisodeRunner")
        self.blackboard.register_key(bb.ANSWER, access=py_trees.common.Access.READ)
        self.control = control or EpisodeControl(b.name for b in root.iterate())
        self.control.wake_with(self.wake.set)
        instrument(root, self.control)

    def run(self) -> EpisodeOutcome:
        """Tick the tree until it answers, fails or runs out of time, recording snapshots as it goes.

        Ctrl-C (SIGINT, a KeyboardInterrupt here) ends it as ``interrupted``, the tree stopped.

        Returns:
            How the episode ended.
        """
        started = time.monotonic()
        ticks = 0
        encoder = SnapshotEncoder(self.run_id)
        try:
            while True:
                interrupt.check()  # a Ctrl-C the last tick's libraries lost
                self.wake.clear()  # what comes in from here on, during the tick too, ends the wait after it
                self.control.before_tick()
                ticks += 1
                tick_started, paused_before_tick = time.perf_counter(), self.control.paused_s
                error = self._tick()
                # a breakpoint inside the tick is not part of it
                tick_ms = (time.perf_counter() - tick_started - (self.control.paused_s - paused_before_tick)) * 1000.0
                if self.timer is not None:
                    self.timer.record("tick", tick_ms)
                self.control.after_tick(ticks)
                outcome = self._outcome(error, ticks, time.monotonic() - started - self.control.paused_s)
                data = encoder.encode(self.tree.root, self.visitor, ticks, tick_ms, last=outcome is not None)
                if data is not None:
                    self._publish(data)
                if outcome is not None:
                    return outcome
                if self.tree.root.status == Status.RUNNING:
                    self._wait(tick_started)
        except KeyboardInterrupt:
            interrupt.clear()
            return EpisodeOutcome("interrupted", f"interrupted (SIGINT) during tick {ticks}", None, ticks,
                                  time.monotonic() - started)
        finally:
            encoder.close()
            self.control.finish()
            self.tree.root.stop(Status.INVALID)  # terminate whatever is still RUNNING
            self.tree.shutdown()

    def _wait(self, tick_started: float) -> None:
        """Wait until something wakes the tree, at most ``max_wait_s``, and at least until
        ``tick_period_s`` has passed since the tick (``tick_started``, perf_counter) began."""
        self.wake.wait(self.max_wait_s)
        rest = tick_started + self.tick_period_s - time.perf_counter()
        if rest > 0:
            time.sleep(rest)  # a pace the settings ask for, to slow the episode down

    def _outcome(self, error: tuple[str, str] | None, ticks: int, elapsed: float) -> EpisodeOutcome | None:
        """How the episode ended on this tick, or None while it goes on."""
        if error is not None:
            return EpisodeOutcome("failed", error[1], None, ticks, elapsed, error[0])
        answer = self.blackboard.get(bb.ANSWER) if self.blackboard.exists(bb.ANSWER) else None
        if answer is not None:
            return EpisodeOutcome("answered", answer["rule"], answer, ticks, elapsed)
        if self.tree.root.status == Status.FAILURE:
            name, reason = self._failure_reason()
            return EpisodeOutcome("failed", reason, None, ticks, elapsed, name)
        if elapsed > self.max_seconds:
            return EpisodeOutcome("failed", f"the episode ran past its limit of {self.max_seconds:g} s",
                                  None, ticks, elapsed)
        return None

    def _tick(self) -> tuple[str, str] | None:
        """Tick once; on an exception, (behaviour name, reason)."""
        try:
            self.tree.tick()
        except Exception as error:
            name = _raising_behaviour(error)
            log.error("behaviour %s raised:\n%s", name, traceback.format_exc())
            return name, f"{name} raised {type(error).__name__}: {error}"
        return None

    def _failure_reason(self) -> tuple[str | None, str]:
        """The deepest behaviour visited this tick that failed, and its feedback message."""
        failed = [b for b in self.tree.root.iterate()
                  if b.id in self.visitor.visited and b.status == Status.FAILURE and not b.children]
        leaf = failed[-1] if failed else None
        return (leaf.name, f"{leaf.name}: {leaf.feedback_message}") if leaf else (None, "the tree failed")

    def _publish(self, data: dict[str, Any]) -> None:
        for sink in self.sinks:
            try:
                sink(data)
            except Exception:  # a broken sink (a full disk, a closed session) must not end the episode
                log.exception("snapshot sink failed")


def _raising_behaviour(error: BaseException) -> str:
    """The name of the innermost behaviour whose method is on the exception's traceback (the
    behaviour it was injected into, for an injected fault)."""
    if isinstance(error, InjectedFault):
        return error.behaviour
    name = "a behaviour"
    frame_tb = error.__traceback__
    while frame_tb is not None:
        candidate = frame_tb.tb_frame.f_locals.get("self")
        if isinstance(candidate, py_trees.behaviour.Behaviour) and not candidate.children:
            name = candidate.name
        frame_tb = frame_tb.tb_next
    return name
