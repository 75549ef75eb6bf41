"""The progress line of a long run (evaluations, suites, training), on stderr.

On a terminal the line is rewritten in place, each update over the last. Written to a log or a
CI job's output, carriage returns would pile every update of a run onto one line thousands of
characters long; there each update is a line of its own, at most one every `LOG_EVERY_S` seconds,
and the last always.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from typing import Any, TextIO

#: How often (s) a progress line is written where the stream is not a terminal.
LOG_EVERY_S = 10.0


class ProgressLine:
    """Shows one run's progress.

    Args:
        stream: where to write (default: `sys.stderr` at the time of each update).
        every_s: the least time between two lines written where the stream is not a terminal.
    """

    def __init__(self, stream: TextIO | None = None, every_s: float = LOG_EVERY_S) -> None:
        self.stream = stream
        self.every_s = every_s
        self._written_at: float | None = None

    def show(self, text: str, last: bool = False) -> None:
        """Show ``text`` as the run's progress now.

        Args:
            text: the line, without indentation or line end.
            last: whether it is the run's last update (or the last of a stage that keeps its line).
        """
        stream = self.stream if self.stream is not None else sys.stderr
        now = time.monotonic()
        if stream.isatty():
            stream.write(f"\r  {text}   " + ("\n" if last else ""))
        elif last or self._written_at is None or now - self._written_at >= self.every_s:
            stream.write(f"  {text}\n")
        else:
            return
        self._written_at = now
        stream.flush()


def counted(unit: str, describe: Callable[[dict[str, Any]], str]) -> Callable[[int, int, dict[str, Any]], None]:
    """A ``progress(done, total, result)`` callback for a run of many results: how many of how many
    ``unit`` are done, and the last one as ``describe`` puts it.

    Args:
        unit: what the run counts ("scenes", "episodes").
        describe: the last result in a few words.

    Returns:
        The callback, with a `ProgressLine` of its own.
    """
    line = ProgressLine()

    def progress(done: int, total: int, result: dict[str, Any]) -> None:
        line.show(f"{done}/{total} {unit}, last {describe(result)}", done == total)

    return progress
