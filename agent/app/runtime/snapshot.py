"""Tree snapshots, version 2: what changed in the tree and on the blackboard, as plain JSON.

`SnapshotEncoder` is asked after every tick and answers a snapshot only when something a viewer
sees changed (a status, a feedback message, the visited path, a blackboard text), and always for
the first and the last tick. A snapshot carries the tree's structure only when it is new, and of
the behaviours and the blackboard only what changed since the last one, so a recorded episode
stays small; a full snapshot (``"full": true``: the structure, every behaviour, every key) comes
first, on a change of structure, and every ``full_every_s`` seconds, so a viewer that joins late
or misses one catches up. `agent.app.tree_state` folds a stream of them back into whole states.
The format is documented in docs/bus.md.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import Any

import py_trees

from agent.app.runtime.board_texts import BoardTexts, writable_by

SNAPSHOT_VERSION = 2

#: py_trees activity types that change the board, and how a snapshot names them.
_WRITES = {"INITIALISED": "init", "WRITE": "set", "ACCESSED": "access", "UNSET": "unset"}


class SnapshotEncoder:
    """Turns the tree after each tick into a version-2 snapshot, or None when nothing visible changed.

    Enables py_trees' blackboard activity stream (and `close` disables it): the writes it records
    between snapshots travel in the next one as ``activity``.

    Args:
        run: the run's id, in every snapshot.
        full_every_s: seconds between full snapshots.
    """

    def __init__(self, run: str, full_every_s: float = 5.0) -> None:
        self.run = run
        self.full_every_s = full_every_s
        self._structure: list[tuple[Any, str, Any]] | None = None
        self._ids: dict[Any, str] = {}
        self._tree: list[dict[str, Any]] = []  # the structure as snapshots carry it
        self._behaviours: dict[str, list[str]] = {}
        self._visited: list[str] = []
        self._board: dict[str, str] = {}
        self._texts = BoardTexts()
        self._activity: list[dict[str, Any]] = []
        self._full_at = 0.0
        py_trees.blackboard.Blackboard.enable_activity_stream(maximum_size=100_000)

    def encode(self, root: py_trees.behaviour.Behaviour, visitor: py_trees.visitors.SnapshotVisitor,
               tick: int, tick_ms: float, last: bool = False) -> dict[str, Any] | None:
        """The snapshot of the tick just ticked (``visitor`` must have run on it), or None if nothing changed.

        Args:
            root: the tree.
            visitor: the visitor that ran on the tick.
            tick: the tick's number.
            tick_ms: how long the tick took.
            last: whether this is the episode's last tick (always answered).

        Returns:
            The snapshot, or None.
        """
        written = self._drain_activity(tick)
        nodes = list(_pre_order(root))
        structure = [(b, b.name, b.parent) for b in nodes]  # the behaviours themselves: compared by identity
        new_structure = structure != self._structure
        full = new_structure or time.monotonic() - self._full_at >= self.full_every_s
        if new_structure:
            self._structure, self._ids = structure, _short_ids([b.id for b in nodes])
            self._tree = [{"id": self._ids[b.id], "name": b.name, "type": type(b).__name__,
                           "parent": self._ids[b.parent.id] if b.parent else None} for b in nodes]
        behaviours = {node["id"]: [b.status.value, b.feedback_message] for node, b in zip(self._tree, nodes)}
        visited = [self._ids[i] for i in visitor.visited if i in self._ids]
        changed = None if written is None else written | writable_by(b for b in nodes if b.id in visitor.visited)
        board = self._texts.texts(py_trees.blackboard.Blackboard.storage, changed)
        changed_behaviours = {i: v for i, v in behaviours.items() if self._behaviours.get(i) != v}
        changed_board = {k: v for k, v in board.items() if self._board.get(k) != v}
        gone = sorted(set(self._board) - set(board))
        if not (full or last or changed_behaviours or changed_board or gone or visited != self._visited):
            return None
        data: dict[str, Any] = {"version": SNAPSHOT_VERSION, "run": self.run, "tick": tick,
                                "tick_ms": round(tick_ms, 3), "status": root.status.value}
        if full:
            self._full_at = time.monotonic()
            data["full"] = True
            data["tree"] = [dict(node) for node in self._tree]
        data["behaviours"] = behaviours if full else changed_behaviours
        data["visited"] = visited
        data["blackboard"] = board if full else changed_board
        if gone and not full:
            data["removed"] = gone
        data["activity"], self._activity = self._activity, []
        self._behaviours, self._visited, self._board = behaviours, visited, board
        return data

    def close(self) -> None:
        """Stop recording blackboard activity."""
        py_trees.blackboard.Blackboard.disable_activity_stream()

    def _drain_activity(self, tick: int) -> set[str] | None:
        """Move this tick's board writes from py_trees' stream into the next snapshot (once per
        key, writer and kind of write); return the keys written (None: no stream, any may have
        changed)."""
        stream = py_trees.blackboard.Blackboard.activity_stream
        if stream is None:
            return None
        written = {item.key for item in stream.data if item.activity_type in _WRITES}
        seen = {(a["tick"], a["key"], a["by"], a["op"]) for a in self._activity if a["tick"] == tick}
        for item in stream.data:
            op = _WRITES.get(item.activity_type)
            if op is None or (tick, item.key, item.client_name, op) in seen:
                continue
            seen.add((tick, item.key, item.client_name, op))
            self._activity.append({"tick": tick, "key": item.key, "by": item.client_name, "op": op})
        stream.clear()
        return written


def _short_ids(ids: list[Any]) -> dict[Any, str]:
    """Each behaviour's id cut to the fewest hex digits (at least 6) that keep them apart."""
    texts = [id_.hex for id_ in ids]
    for length in range(6, 33):
        short = [text[:length] for text in texts]
        if len(set(short)) == len(short):
            return dict(zip(ids, short))
    return dict(zip(ids, texts))


def _pre_order(root: py_trees.behaviour.Behaviour) -> Iterator[py_trees.behaviour.Behaviour]:
    """Parents before their children, children in tick order (py_trees' iterate() is post-order)."""
    stack = [root]
    while stack:
        behaviour = stack.pop()
        yield behaviour
        stack.extend(reversed(behaviour.children))
