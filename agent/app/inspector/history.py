"""The whole states of one run's tree, tick by tick, shared between the thread that fills it and
the HTTP threads that read it."""

from __future__ import annotations

import threading
from typing import Any

from agent.app.tree_state import TreeState


class History:
    """Every whole state so far, in order; readers wait for new ones.

    Args:
        limit: the most states kept (the oldest go first).
    """

    def __init__(self, limit: int = 20_000) -> None:
        self.limit = limit
        self._tree = TreeState()
        self._states: list[dict[str, Any]] = []
        self._dropped = 0
        self._changed = threading.Condition()

    def add(self, snapshot: dict[str, Any]) -> None:
        """Apply one checked snapshot; its whole state becomes the newest.

        Args:
            snapshot: the snapshot.
        """
        with self._changed:
            state = self._tree.apply(snapshot)
            if state is None:
                return
            if self._states and self._states[-1]["run"] != state["run"]:  # a new run: start over
                self._dropped += len(self._states)
                self._states = []
            self._states.append(state)
            if len(self._states) > self.limit:
                self._states.pop(0)
                self._dropped += 1
            self._changed.notify_all()

    def since(self, index: int, wait_s: float = 0.0) -> tuple[list[dict[str, Any]], int]:
        """The states from position ``index`` on (positions count from the run's first state), waiting
        up to ``wait_s`` for one when there are none yet.

        Args:
            index: the first position wanted.
            wait_s: how long to wait for a new state.

        Returns:
            The states and the position after the last of them.
        """
        with self._changed:
            if self._dropped + len(self._states) <= index and wait_s > 0:
                self._changed.wait(wait_s)
            start = max(index, self._dropped) - self._dropped
            return self._states[start:], self._dropped + len(self._states)
