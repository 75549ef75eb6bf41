"""Controlling a running episode from outside: pause, step, breakpoints and injected faults.

`EpisodeControl` is shared by the thread that ticks the tree and the thread that answers control
requests. The ticking thread asks it before every tick (`before_tick`) and before every behaviour
ticks (`before_behaviour`, through the per-instance wrapper `instrument` puts on each behaviour's
``tick``); while the episode is paused it waits there on a condition, never spinning, and the time
spent so is not counted against the episode's wall-clock limit. A request also calls the wake the
runner registered (`wake_with`), so a tree waiting between ticks for a reply comes to it at once. Requests name behaviours by name;
a name the tree does not hold is refused, listing the names it does.

A pending fault takes effect on the behaviour's next tick: ``failure`` makes that tick return
FAILURE without running the behaviour (feedback message "injected failure"), ``raise`` raises
`InjectedFault` in the behaviour's tick, which the runner records like any behaviour's exception.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Iterator
from typing import Any

import py_trees
from py_trees.common import Status

#: What `EpisodeControl.inject` can make a behaviour do on its next tick.
FAULTS = ("failure", "raise")
INJECTED_FAILURE = "injected failure"


class ControlRefused(ValueError):
    """A control request that cannot be carried out; the text is ``<field>: <problem>``."""


class InjectedFault(RuntimeError):
    """What an injected ``raise`` fault raises inside the behaviour's tick.

    Args:
        behaviour: the behaviour's name.
        tick: the tick it was raised on.
    """

    def __init__(self, behaviour: str, tick: int) -> None:
        super().__init__(f"injected into {behaviour} on tick {tick}")
        self.behaviour = behaviour


class EpisodeControl:
    """Pause, step, breakpoints and pending faults of one episode, safe to use from any thread.

    Args:
        behaviours: the names of the tree's behaviours (requests naming others are refused).
    """

    def __init__(self, behaviours: Iterable[str]) -> None:
        self._names = sorted(set(behaviours))
        self._condition = threading.Condition()
        self._paused = False
        self._paused_before: str | None = None
        self._step_until: int | None = None  # pause again once this many ticks are done
        self._ticks = 0
        self._waiting = False
        self._waits = 0  # how many times the tree has started waiting
        self._finished = False
        self._paused_s = 0.0
        self._breakpoints: set[str] = set()
        self._faults: dict[str, str] = {}
        self._injected: list[dict[str, Any]] = []
        self._wake: Callable[[], None] = lambda: None

    def wake_with(self, wake: Callable[[], None]) -> None:
        """Call ``wake`` whenever a request asks the ticking thread to do something (pause, go on,
        step, inject), and when a step pauses the tree: the runner's wait between ticks ends then.

        Args:
            wake: ends the ticking thread's wait between ticks.
        """
        self._wake = wake

    # Requests (any thread).

    def state(self) -> dict[str, Any]:
        """Where the episode stands, as every control reply carries it.

        Returns:
            ``{"paused", "tick", "paused_before", "breakpoints", "faults", "injected"}``.
        """
        with self._condition:
            return {"paused": self._paused, "tick": self._ticks, "paused_before": self._paused_before,
                    "breakpoints": sorted(self._breakpoints),
                    "faults": [{"behaviour": name, "fault": fault} for name, fault in self._faults.items()],
                    "injected": [dict(entry) for entry in self._injected]}

    def pause(self, settle_s: float = 0.0) -> None:
        """Pause before the next tick; wait up to ``settle_s`` for the tree to stop there.

        Args:
            settle_s: how long to wait for the tick in progress to finish.
        """
        with self._condition:
            self._paused = True
            self._step_until = None
            self._wake()
            self._settle(None, settle_s)

    def resume(self) -> None:
        """Let the tree run freely (the ``continue`` request)."""
        with self._condition:
            self._paused = False
            self._step_until = None
            self._paused_before = None
            self._condition.notify_all()
        self._wake()

    def step(self, settle_s: float = 0.0) -> None:
        """Run until the next tick boundary, then pause; wait up to ``settle_s`` for it.

        Paused between ticks, that is exactly one tick; paused before a behaviour, the rest of the
        tick in progress. A breakpoint on the way pauses there.

        Args:
            settle_s: how long to wait for the tree to stop again.

        Raises:
            ControlRefused: the episode is not paused.
        """
        with self._condition:
            if not self._paused:
                raise ControlRefused("step: the episode is not paused (pause it first)")
            self._paused = False
            self._paused_before = None
            self._step_until = self._ticks + 1
            self._condition.notify_all()
            self._wake()
            self._settle(self._waits, settle_s)

    def set_breakpoint(self, behaviour: str, on: bool) -> None:
        """Pause right before ``behaviour`` ticks, every time (``on``), or no longer.

        Args:
            behaviour: the behaviour's name.
            on: whether to set or clear the breakpoint.

        Raises:
            ControlRefused: the tree has no behaviour of that name.
        """
        self._check_name("breakpoint.behaviour", behaviour)
        with self._condition:
            if on:
                self._breakpoints.add(behaviour)
            else:
                self._breakpoints.discard(behaviour)

    def inject(self, behaviour: str, fault: str) -> None:
        """Make ``behaviour``'s next tick fail (``failure``) or raise `InjectedFault` (``raise``).

        Args:
            behaviour: the behaviour's name.
            fault: ``failure`` or ``raise``.

        Raises:
            ControlRefused: an unknown behaviour or fault.
        """
        self._check_name("inject.behaviour", behaviour)
        if fault not in FAULTS:
            raise ControlRefused(f"inject.fault: expected one of {', '.join(FAULTS)}, got {fault!r}")
        with self._condition:
            self._faults[behaviour] = fault
        self._wake()

    # The ticking thread.

    @property
    def paused_s(self) -> float:
        """The seconds the tree has spent waiting while paused."""
        with self._condition:
            return self._paused_s

    @property
    def injected(self) -> list[dict[str, Any]]:
        """What was injected: ``[{"tick", "behaviour", "fault"}]``, in order."""
        with self._condition:
            return [dict(entry) for entry in self._injected]

    def before_tick(self) -> None:
        """Wait while the episode is paused between ticks."""
        with self._condition:
            self._wait_while_paused(None)

    def after_tick(self, ticks: int) -> None:
        """Record that ``ticks`` ticks are done; a step that reached its boundary pauses here.

        Args:
            ticks: the ticks done so far.
        """
        with self._condition:
            self._ticks = ticks
            if self._step_until is not None and ticks >= self._step_until:
                self._paused = True
                self._step_until = None
                self._wake()

    def before_behaviour(self, behaviour: str) -> dict[str, Any] | None:
        """Wait at a breakpoint on ``behaviour``; then take its pending fault, if any.

        Args:
            behaviour: the name of the behaviour about to tick.

        Returns:
            The fault to inject now, ``{"tick", "behaviour", "fault"}`` (recorded as injected), or None.
        """
        with self._condition:
            if behaviour in self._breakpoints:
                self._paused = True
                self._wait_while_paused(behaviour)
            fault = self._faults.pop(behaviour, None)
            if fault is None:
                return None
            self._injected.append({"tick": self._ticks + 1, "behaviour": behaviour, "fault": fault})
            return dict(self._injected[-1])

    def finish(self) -> None:
        """Say the episode is over, so that nothing waits for it to stop."""
        with self._condition:
            self._finished = True
            self._condition.notify_all()

    def _wait_while_paused(self, before: str | None) -> None:
        if not self._paused:
            return
        started = time.monotonic()
        self._paused_before, self._waiting = before, True
        self._waits += 1
        self._condition.notify_all()
        while self._paused:
            self._condition.wait()
        self._paused_before, self._waiting = None, False
        self._paused_s += time.monotonic() - started

    def _settle(self, waits: int | None, settle_s: float) -> None:
        """Wait up to ``settle_s`` until the tree waits (a new wait when ``waits`` is given), runs
        freely or is over."""
        def settled() -> bool:
            stopped = self._waiting and (waits is None or self._waits > waits)
            return stopped or self._finished or (not self._paused and self._step_until is None)

        self._condition.wait_for(settled, timeout=settle_s)

    def _check_name(self, field: str, behaviour: Any) -> None:
        if not isinstance(behaviour, str):
            raise ControlRefused(f"{field}: expected a behaviour's name, got {behaviour!r}")
        if behaviour not in self._names:
            raise ControlRefused(f"{field}: {behaviour!r} is not a behaviour of the tree; "
                                 f"its behaviours: {', '.join(self._names)}")


def instrument(root: py_trees.behaviour.Behaviour, control: EpisodeControl) -> None:
    """Put `control` in front of every behaviour's tick in the tree (composites tick their
    children through ``child.tick()``, so each instance's ``tick`` is replaced).

    Args:
        root: the tree.
        control: the episode's control.
    """
    for behaviour in root.iterate():
        behaviour.tick = _controlled_tick(behaviour, behaviour.tick, control)  # type: ignore[method-assign]


def _controlled_tick(behaviour: py_trees.behaviour.Behaviour,
                     tick: Callable[[], Iterator[py_trees.behaviour.Behaviour]],
                     control: EpisodeControl) -> Callable[[], Iterator[py_trees.behaviour.Behaviour]]:
    """``behaviour``'s tick with the control's breakpoint and fault in front of it."""
    def controlled() -> Iterator[py_trees.behaviour.Behaviour]:
        injected = control.before_behaviour(behaviour.name)
        if injected is None:
            yield from tick()
        elif injected["fault"] == "raise":
            raise InjectedFault(behaviour.name, injected["tick"])
        else:  # "failure": what py_trees does when update returns FAILURE, without update
            for child in behaviour.children:
                if child.status == Status.RUNNING:
                    child.stop(Status.INVALID)
            behaviour.stop(Status.FAILURE)
            behaviour.feedback_message = INJECTED_FAILURE
            yield behaviour
    return controlled
