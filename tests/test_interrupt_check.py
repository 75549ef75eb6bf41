"""A Ctrl-C that library code drops still ends the loop that checks for it (`agent.app.runtime.interrupt`)."""

from __future__ import annotations

import signal
from collections.abc import Iterator

import numpy as np
import pytest

from agent.app.runtime import interrupt

NAMES = ["kitchen", "books", "toys", "tools"]
#: Units of work a loop below runs at most; one takes a fraction of a millisecond.
UNITS = 400


class _Loop:
    """The units a loop below has begun, and how many had begun when the Ctrl-C came."""

    units = 0
    at_signal: int | None = None


@pytest.fixture
def ctrl_c_by_timer() -> Iterator[None]:
    """`interrupt.on_sigint` installed for SIGINT, and also for SIGALRM, so a one-shot timer can
    deliver a Ctrl-C at a moment that falls inside library code; the unit it landed in is noted."""
    before = {number: signal.getsignal(number) for number in (signal.SIGINT, signal.SIGALRM)}
    interrupt.install()

    def ctrl_c(signum: int, frame: object) -> None:
        _Loop.at_signal = _Loop.units
        interrupt.on_sigint(signum, None)

    signal.signal(signal.SIGALRM, ctrl_c)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        for number, handler in before.items():
            signal.signal(number, handler)
        interrupt.clear()


def _units_until_interrupted(rng: np.random.Generator, delay_s: float, check: bool) -> int:
    """Run units of ``rng.choice`` over names, a Ctrl-C due after ``delay_s``; the units begun
    after the one the Ctrl-C landed in, before the KeyboardInterrupt came out of the loop
    (`UNITS` + 1 if it never did)."""
    _Loop.units, _Loop.at_signal = 0, None
    interrupt.clear()  # a Ctrl-C the last loop took as raised is noted still
    try:
        signal.setitimer(signal.ITIMER_REAL, delay_s)
        while _Loop.units < UNITS:
            _Loop.units += 1
            for _ in range(20):
                rng.choice(NAMES, p=[0.4, 0.3, 0.2, 0.1])
            if check:
                interrupt.check()
        return UNITS + 1
    except KeyboardInterrupt:
        assert _Loop.at_signal is not None
        return _Loop.units - _Loop.at_signal
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)


def test_numpy_drops_some_interrupts_raised_inside_choice(ctrl_c_by_timer: None) -> None:
    """Why the check exists: without it, some Ctrl-Cs that land in ``Generator.choice`` never reach
    the loop. Should a numpy release stop dropping them, this test says so and `interrupt` can go."""
    rng = np.random.default_rng(0)
    lost = sum(_units_until_interrupted(rng, 0.0005 + 0.0001 * trial, check=False) > UNITS for trial in range(30))
    assert lost > 0


def test_a_dropped_ctrl_c_is_raised_at_the_next_check(ctrl_c_by_timer: None) -> None:
    rng = np.random.default_rng(0)
    for trial in range(30):
        late = _units_until_interrupted(rng, 0.0005 + 0.0001 * trial, check=True)
        assert late <= 1, f"trial {trial}: the Ctrl-C came out {late} units after the one it landed in"
    with pytest.raises(KeyboardInterrupt):  # one raised by the handler is noted for check as well
        interrupt.on_sigint(signal.SIGINT, None)
    with pytest.raises(KeyboardInterrupt):
        interrupt.check()
    interrupt.check()  # raised once, then forgotten


def test_a_handled_ctrl_c_is_not_raised_again() -> None:
    with pytest.raises(KeyboardInterrupt):
        interrupt.on_sigint(signal.SIGINT, None)
    interrupt.clear()
    interrupt.check()


def test_an_episode_ends_on_a_ctrl_c_its_tick_dropped_and_forgets_it() -> None:
    """A leaf whose library swallows the Ctrl-C: the episode ends as ``interrupted`` before the
    next tick, and, having handled it, leaves nothing for the next `check`."""
    import py_trees

    from agent.app.runtime.episode import EpisodeRunner

    class DropsCtrlC(py_trees.behaviour.Behaviour):
        def update(self) -> py_trees.common.Status:
            try:
                interrupt.on_sigint(signal.SIGINT, None)
            except KeyboardInterrupt:
                pass
            return py_trees.common.Status.RUNNING

    outcome = EpisodeRunner(DropsCtrlC("drops Ctrl-C"), "test", [], max_seconds=30.0).run()
    assert outcome.status == "interrupted" and outcome.ticks == 1  # not a second tick
    interrupt.check()
