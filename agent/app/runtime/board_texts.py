"""The blackboard's readable texts for snapshots, rendered again only for keys that may have changed.

Rendering every key after every tick (`agent.app.runtime.readable`) costs most of a snapshot. A key's
text is kept from the last time and rendered again only when its value may have changed since: the
key holds another object, or it was written (py_trees' activity stream: set, or got for writing,
which is how a leaf changes an object in place), or a behaviour that may write it ticked (through
an object it holds since an earlier tick, or its worker while it is RUNNING, it can change the
value without the board seeing it).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

import py_trees

from agent.app.runtime.readable import readable


class BoardTexts:
    """Each blackboard key's readable text, remembered with the object it was rendered from."""

    def __init__(self) -> None:
        self._rendered: dict[str, tuple[Any, str]] = {}

    def texts(self, storage: Mapping[str, Any], changed: Iterable[str] | None) -> dict[str, str]:
        """The text of every key on the board, in key order.

        Args:
            storage: the blackboard's storage, key -> value.
            changed: the keys whose values may have changed in place since the last call; None
                when that is not known (every key is rendered).

        Returns:
            key -> readable text.
        """
        changed = set(storage) if changed is None else set(changed)
        texts: dict[str, str] = {}
        rendered: dict[str, tuple[Any, str]] = {}
        for key in sorted(storage):
            value = storage[key]
            kept = self._rendered.get(key)
            if kept is None or kept[0] is not value or key in changed:
                kept = (value, readable(value))
            rendered[key] = kept
            texts[key] = kept[1]
        self._rendered = rendered
        return texts


def writable_by(behaviours: Iterable[py_trees.behaviour.Behaviour]) -> set[str]:
    """The blackboard keys that ``behaviours`` may write.

    Args:
        behaviours: behaviours of the tree.

    Returns:
        The keys, as the board stores them.
    """
    keys: set[str] = set()
    for behaviour in behaviours:
        for client in behaviour.blackboards:
            keys.update(client.remappings.get(key, key) for key in (*client.write, *client.exclusive))
    return keys
