"""Tree snapshots: what every behaviour is doing on one tick, as plain JSON.

One snapshot names every behaviour (id, name, type, parent, status, feedback message), the path
visited on that tick, the tick count and duration, and the blackboard keys that the visited
behaviours use, each as a short string. `homebot watch` renders them; scripts read them.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from typing import Any

import numpy as np
import py_trees

SNAPSHOT_VERSION = 1
_SHORT = 72


def short(value: Any) -> str:
    """A one-line description of a blackboard value that stays readable for large objects.

    Args:
        value: the value.

    Returns:
        The description.
    """
    if isinstance(value, np.ndarray):
        return f"array{list(value.shape)} {value.dtype}"
    if isinstance(value, (list, tuple)) and len(value) > 4:
        return f"{type(value).__name__} of {len(value)}, last {short(value[-1])}"
    if hasattr(value, "__len__") and not isinstance(value, (str, list, tuple, dict)):
        return f"<{type(value).__name__} of {len(value)}>"
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return f"<{type(value).__name__}>"
    text = repr(value)
    return text if len(text) <= _SHORT else text[: _SHORT - 1] + "…"


def snapshot(root: py_trees.behaviour.Behaviour, visitor: py_trees.visitors.SnapshotVisitor,
             tick: int, tick_ms: float, run: str) -> dict[str, Any]:
    """The JSON-able snapshot of the tree just ticked (``visitor`` must have run on that tick).

    Args:
        root: the tree.
        visitor: the visitor that ran on the tick.
        tick: the tick's number.
        tick_ms: how long the tick took.
        run: the run's id.

    Returns:
        The snapshot.
    """
    behaviours = []
    for behaviour in _pre_order(root):
        behaviours.append({
            "id": str(behaviour.id),
            "name": behaviour.name,
            "type": type(behaviour).__name__,
            "parent": str(behaviour.parent.id) if behaviour.parent else None,
            "status": behaviour.status.value,
            "message": behaviour.feedback_message,
            "visited": behaviour.id in visitor.visited,
        })
    storage = py_trees.blackboard.Blackboard.storage
    keys = sorted(visitor.visited_blackboard_keys)
    return {
        "version": SNAPSHOT_VERSION,
        "run": run,
        "tick": tick,
        "tick_ms": round(tick_ms, 3),
        "status": root.status.value,
        "visited_path": [str(i) for i in visitor.visited],
        "behaviours": behaviours,
        "blackboard": {key: short(storage[key]) for key in keys if key in storage},
    }


def _pre_order(behaviour: py_trees.behaviour.Behaviour) -> Iterator[py_trees.behaviour.Behaviour]:
    """Parents before their children, children in tick order (py_trees' iterate() is post-order)."""
    yield behaviour
    for child in behaviour.children:
        yield from _pre_order(child)
