"""Knowing whether the world is still there, from its Zenoh liveliness token."""

from __future__ import annotations

import threading
import time

import zenoh


class LivenessWatch:
    """Follows one liveliness token; `gone` gives a reason once the token has been seen and lost.

    Args:
        session: the bus session.
        key: the token's key.
    """

    def __init__(self, session: zenoh.Session, key: str) -> None:
        self.key = key
        self._lock = threading.Lock()
        self._alive = threading.Event()  # set while the token is there
        self._lost_at: float | None = None
        self._subscriber = session.liveliness().declare_subscriber(key, self._on_sample, history=True)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._lost_at = None
                self._alive.set()
            else:
                self._lost_at = time.monotonic()
                self._alive.clear()

    @property
    def alive(self) -> bool:
        return self._alive.is_set()

    def gone(self) -> str | None:
        """Why the world is gone, once its liveliness token has been dropped; None while it is there.

        Returns:
            The reason, or None.
        """
        with self._lock:
            if self._lost_at is None:
                return None
        return f"the world process is gone (its liveliness token {self.key} was dropped)"

    def wait_alive(self, timeout_s: float) -> bool:
        """Wait until the token is present, at most ``timeout_s``; return as soon as it comes.

        Args:
            timeout_s: how long to wait.

        Returns:
            Whether the token is present.
        """
        return self._alive.wait(timeout_s)

    def close(self) -> None:
        self._subscriber.undeclare()
