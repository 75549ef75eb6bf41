"""Ctrl-C that library code cannot lose.

Python turns SIGINT into a KeyboardInterrupt raised wherever the main thread happens to be, and
some compiled code drops an exception raised under it: numpy 2.4's ``Generator.choice`` over a
list or array of items loses about two of three (measured: 500 signals during ``rng.choice(names,
p=...)``, 140 interrupts reached the caller). A Ctrl-C that lands there would do nothing, and a
command would run on to its end. So the `homebot` command records each Ctrl-C as well as raising it
(`on_sigint`), and its long loops call `check` once per unit of work (a scenario written, a tick, a
result appended): a Ctrl-C that was lost is raised there instead, at most one unit late.

Only the command installs `on_sigint`; where it is not installed, `check` never raises, so code
that uses these loops as a library keeps Python's own Ctrl-C.
"""

from __future__ import annotations

import signal
import threading
from types import FrameType

_requested = threading.Event()


def on_sigint(signum: int, frame: FrameType | None) -> None:
    """The SIGINT handler: note the Ctrl-C for `check`, and raise it as Python's own handler does.

    Args:
        signum: the signal's number (SIGINT).
        frame: the frame it interrupted (unused).

    Raises:
        KeyboardInterrupt: always, as Python's own handler does.
    """
    _requested.set()
    raise KeyboardInterrupt


def install() -> None:
    """Make `on_sigint` this process's SIGINT handler (call from the main thread)."""
    signal.signal(signal.SIGINT, on_sigint)


def check() -> None:
    """Raise the Ctrl-C that came since the last `check` or `clear`, in case nothing raised it.

    Raises:
        KeyboardInterrupt: a Ctrl-C came.
    """
    if _requested.is_set():
        _requested.clear()
        raise KeyboardInterrupt


def clear() -> None:
    """Forget a Ctrl-C that was handled: code that takes a KeyboardInterrupt and goes on (an
    episode that ends as ``interrupted``) calls this, so that the next `check` does not raise it
    again."""
    _requested.clear()
