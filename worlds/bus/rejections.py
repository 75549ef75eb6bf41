"""A server's log of the requests it refused: one line each, at most a few lines a second.

A client that sends malformed requests in a loop must not fill the disk or the server's memory
with its log: every refusal is one line (never a traceback), lines beyond the rate are counted
instead of written, and the count comes in one line when logging resumes or the server is idle.
An internal error (a bug, not a bad request) is one line too; its traceback is logged the first
time it comes from a place, so the bug can be found without a flood of copies.
"""

from __future__ import annotations

import logging
import threading
import time
import traceback
from collections.abc import Callable

#: The longest reason written in one line; the client's reply carries it whole.
MAX_REASON_CHARS = 300
_MAX_ORIGINS = 100


def _cut(text: str) -> str:
    text = text.replace("\n", " | ")
    return text if len(text) <= MAX_REASON_CHARS else f"{text[:MAX_REASON_CHARS]}… ({len(text)} characters)"


class RejectionLog:
    """Rate-limited lines about refused requests, safe to call from several threads.

    Args:
        logger: where the lines go.
        per_second: the lines written a second, on average.
        burst: the lines that may come at once after a quiet while.
        clock: seconds, monotonic (for tests that step time).
    """

    def __init__(self, logger: logging.Logger, per_second: float = 10.0, burst: int = 20,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self._log = logger
        self._per_second = per_second
        self._burst = burst
        self._clock = clock
        self._lock = threading.Lock()
        self._tokens = float(burst)
        self._last = clock()
        self._suppressed = 0
        self._since: float | None = None
        self._origins: set[tuple[str, str, int]] = set()

    @property
    def suppressed(self) -> int:
        """Lines counted but not written since the last one that was.

        Returns:
            The count.
        """
        with self._lock:
            return self._suppressed

    def rejected(self, key: str, reason: str) -> None:
        """One line: the request on ``key`` was refused for ``reason``.

        Args:
            key: the key the request came on.
            reason: what the client was told.
        """
        self._write(logging.INFO, f"rejected {key}: {_cut(reason)}")

    def failed(self, key: str, error: BaseException) -> None:
        """One line: answering the request on ``key`` raised ``error``; its traceback the first time
        an error of that type comes from that place.

        Args:
            key: the key the request came on.
            error: what the handler raised.
        """
        frames = traceback.extract_tb(error.__traceback__)
        origin = (type(error).__name__, frames[-1].filename, frames[-1].lineno or 0) if frames else ("", "", 0)
        with self._lock:
            first = origin not in self._origins and len(self._origins) < _MAX_ORIGINS
            self._origins.add(origin)
        self._write(logging.ERROR, f"internal error answering {key}: {type(error).__name__}: {_cut(str(error))}",
                    error if first else None)

    def flush(self) -> None:
        """Write the count of lines held back, once the rate allows a line (for an idle server)."""
        with self._lock:
            if self._suppressed and self._take():
                self._write_count()

    def _write(self, level: int, line: str, error: BaseException | None = None) -> None:
        with self._lock:
            if not self._take():
                self._suppressed += 1
                if self._since is None:
                    self._since = self._clock()
                return
            if self._suppressed:
                self._write_count()
            self._log.log(level, "%s", line, exc_info=error)

    def _take(self) -> bool:
        now = self._clock()
        self._tokens = min(float(self._burst), self._tokens + (now - self._last) * self._per_second)
        self._last = now
        if self._tokens < 1.0:
            return False
        self._tokens -= 1.0
        return True

    def _write_count(self) -> None:
        held = self._clock() - (self._since if self._since is not None else self._clock())
        self._log.info("%d more refused requests not logged in the last %.1f s (at most %g lines a second)",
                          self._suppressed, held, self._per_second)
        self._suppressed, self._since = 0, None
