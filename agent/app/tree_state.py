"""Reading version-2 tree snapshots: check one off the wire, and fold a stream into whole states.

A snapshot carries only what changed (`agent.app.runtime.snapshot`); `TreeState` keeps the last
whole state and applies each snapshot to it, so `homebot watch`, `homebot inspect` and tests see
every tick as a full tree: structure, every behaviour's status and message, the visited path,
every blackboard text and that snapshot's blackboard activity.
"""

from __future__ import annotations

import copy
import json
from collections.abc import Iterable
from typing import Any

VERSION = 2


class SnapshotError(ValueError):
    """A snapshot that is not the JSON object a version-2 tree snapshot must be; the text names the field."""


def parse_snapshot(payload: bytes) -> dict[str, Any]:
    """Decode one snapshot and check it (never evaluated, only parsed).

    Args:
        payload: the sample's bytes.

    Returns:
        The snapshot.

    Raises:
        SnapshotError: the payload is not a snapshot.
    """
    try:
        data = json.loads(payload.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise SnapshotError(f"snapshot: not UTF-8 JSON ({error})") from None
    return check_snapshot(data)


def check_snapshot(data: Any) -> dict[str, Any]:
    """Check a decoded snapshot's fields.

    Args:
        data: the decoded JSON.

    Returns:
        ``data``.

    Raises:
        SnapshotError: a field is missing or of the wrong kind.
    """
    if not isinstance(data, dict):
        raise SnapshotError("snapshot: expected a JSON object")
    if data.get("version") != VERSION:
        raise SnapshotError(f"snapshot.version: expected {VERSION}, got {data.get('version')!r}")
    kinds = {"run": str, "tick": int, "status": str, "behaviours": dict, "visited": list, "blackboard": dict,
             "activity": list}
    for field, kind in kinds.items():
        if not isinstance(data.get(field), kind):
            raise SnapshotError(f"snapshot.{field}: expected {kind.__name__}, got {type(data.get(field)).__name__}")
    for node_id, entry in data["behaviours"].items():
        if not (isinstance(entry, list) and len(entry) == 2 and all(isinstance(part, str) for part in entry)):
            raise SnapshotError(f"snapshot.behaviours.{node_id}: expected [status, message]")
    tree = data.get("tree")
    if tree is not None and not (isinstance(tree, list) and all(
            isinstance(node, dict) and isinstance(node.get("id"), str) and isinstance(node.get("name"), str)
            for node in tree)):
        raise SnapshotError("snapshot.tree: expected a list of {id, name, type, parent}")
    if data.get("full") and tree is None:
        raise SnapshotError("snapshot.tree: a full snapshot must carry the tree")
    return data


class TreeState:
    """The last whole state of a run's tree, with each snapshot applied in turn."""

    def __init__(self) -> None:
        self.state: dict[str, Any] | None = None

    def apply(self, data: dict[str, Any]) -> dict[str, Any] | None:
        """Apply one snapshot; the whole state after it, or None until a full snapshot of its run came.

        Args:
            data: a checked snapshot.

        Returns:
            The whole state (a new object; earlier ones are left as they were), or None.
        """
        if data.get("full"):
            self.state = {"tree": data["tree"], "behaviours": {}, "blackboard": {}}
        elif self.state is None or self.state["run"] != data["run"]:
            self.state = None
            return None
        previous = self.state
        tree = data.get("tree", previous["tree"])
        ids = {node["id"] for node in tree}
        behaviours = {i: v for i, v in {**previous["behaviours"], **data["behaviours"]}.items() if i in ids}
        blackboard = {**previous["blackboard"], **data["blackboard"]}
        for key in data.get("removed", []):
            blackboard.pop(key, None)
        self.state = {"version": VERSION, "run": data["run"], "tick": data["tick"],
                      "tick_ms": data.get("tick_ms", 0.0), "status": data["status"], "tree": tree,
                      "behaviours": behaviours, "visited": data["visited"], "blackboard": blackboard,
                      "activity": data["activity"]}
        return copy.copy(self.state)


def fold(snapshots: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """Whole states, one per snapshot, from a run's snapshots in order (those before the first full one skipped).

    Args:
        snapshots: checked snapshots.

    Returns:
        The states.
    """
    state = TreeState()
    return [whole for whole in map(state.apply, snapshots) if whole is not None]


def read_log(text: str) -> list[dict[str, Any]]:
    """The checked snapshots of a snapshots.jsonl file's text.

    Args:
        text: the file's text.

    Returns:
        The snapshots, in order.

    Raises:
        SnapshotError: a line is not a snapshot (the text names the line).
    """
    snapshots = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip():
            continue
        try:
            snapshots.append(parse_snapshot(line.encode("utf-8")))
        except SnapshotError as error:
            raise SnapshotError(f"line {number}: {error}") from None
    return snapshots


def behaviour_rows(state: dict[str, Any]) -> list[dict[str, Any]]:
    """The state's behaviours in tree order as rows: id, name, type, parent, status, message, visited.

    Args:
        state: a whole state.

    Returns:
        The rows.
    """
    visited = set(state["visited"])
    return [{**node, "status": state["behaviours"].get(node["id"], ["INVALID", ""])[0],
             "message": state["behaviours"].get(node["id"], ["INVALID", ""])[1], "visited": node["id"] in visited}
            for node in state["tree"]]
