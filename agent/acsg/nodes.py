"""What an action-conditioned scene graph is made of: object nodes, action nodes and edges.

An object node is what is there (semantics and geometry), an action node what can be done to one
(a high-level type and the low-level primitive that does it). Edges come in the paper's four
kinds, named as in the ground truth of `worlds.tabletop_scene`:

- ``object-object``: parent to child, naming the child's relation to it (belongs, on, inside, under);
- ``object-action``: the object can be acted on ("can be opened", "can be picked");
- ``action-object``: the action reveals the object (one level deep: what it makes visible);
- ``action-action``: precondition (move the condiment away before opening the door).

Each node reads and writes its own JSON entry; a bad field raises `ACSGError` naming it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np

from agent.acsg.primitives import UNDO

OBJECT_RELATIONS = ("belongs", "on", "inside", "under")
#: edge kind -> (source node kind, target node kind)
EDGE_KINDS: dict[str, tuple[str, str]] = {
    "object-object": ("object", "object"),
    "object-action": ("object", "action"),
    "action-object": ("action", "object"),
    "action-action": ("action", "action"),
}
ACTION_TYPES = ("open", "close", "pick", "place", "look")
ACTION_STATES = ("unexplored", "explored", "failed")
_ACTION_RELATION = {"open": "can be opened", "pick": "can be picked"}


class ACSGError(ValueError):
    """A graph, node or edge that breaks the ACSG's rules; the text names the field."""


def _vector(node_id: str, name: str, value: Any, shape: tuple[int | None, ...]) -> np.ndarray | None:
    """``value`` as a float array of ``shape`` (None: any length), or None; a bad one names the field."""
    if value is None:
        return None
    array = np.asarray(value, dtype=float)
    if array.ndim != len(shape) or any(want is not None and got != want for got, want in zip(array.shape, shape)):
        want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
        raise ACSGError(f"object {node_id}: {name} must have shape {want}, got {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ACSGError(f"object {node_id}: {name} holds a non-finite value")
    return array


@dataclass(eq=False)
class ObjectNode:
    """o_i = (s_i, p_i): a label standing for the semantics, optional geometry, free attributes.

    ``instance`` is the perception's instance id (a tracker id on a robot, the simulator's id in a
    scene); ``explored`` is the paper's per-node flag: the decision module has judged it.
    ``points`` (N, 3) world points, ``centroid`` (3,), ``extent`` (3,) the full size of the
    axis-aligned box.

    Raises:
        ACSGError: an empty id or label, or geometry of the wrong shape or not finite.
    """

    id: str
    label: str
    instance: str | None = None
    attributes: dict[str, Any] = field(default_factory=dict)
    points: np.ndarray | None = None
    centroid: np.ndarray | None = None
    extent: np.ndarray | None = None
    explored: bool = False

    kind: ClassVar[str] = "object"

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not self.id:
            raise ACSGError(f"object id: must be a non-empty string, got {self.id!r}")
        if not isinstance(self.label, str) or not self.label:
            raise ACSGError(f"object {self.id}: label must be a non-empty string, got {self.label!r}")
        if self.instance is not None:
            self.instance = str(self.instance)
        self.points = _vector(self.id, "points", self.points, (None, 3))
        self.centroid = _vector(self.id, "centroid", self.centroid, (3,))
        self.extent = _vector(self.id, "extent", self.extent, (3,))

    def describe(self) -> str:
        """The object as a person names it, for prompts and messages.

        Returns:
            "colour label" when the colour is known, else the label.
        """
        colour = self.attributes.get("colour")
        return f"{colour} {self.label}" if colour else self.label

    def to_dict(self) -> dict[str, Any]:
        """The object's JSON entry.

        Returns:
            A JSON-able dict; geometry only where known.
        """
        data: dict[str, Any] = {"id": self.id, "kind": "object", "label": self.label}
        if self.instance is not None:
            data["instance"] = self.instance
        data["attributes"] = dict(self.attributes)
        data["explored"] = self.explored
        for name in ("centroid", "extent", "points"):
            value = getattr(self, name)
            if value is not None:
                data[name] = value.tolist()
        return data

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ObjectNode:
        """Read an object's JSON entry back; absent optional fields take their defaults.

        Args:
            data: an entry written by `to_dict` (or by hand, with only id and label).

        Returns:
            The object node.
        """
        return cls(
            id=data["id"], label=data["label"], instance=data.get("instance"),
            attributes=dict(data.get("attributes", {})), points=data.get("points"),
            centroid=data.get("centroid"), extent=data.get("extent"), explored=bool(data.get("explored", False)),
        )


@dataclass(eq=False)
class ActionNode:
    """a_k = (a_k, T_k): the high-level ``type`` on the object ``target`` and the low-level
    ``primitive`` with its ``params`` (which handle to pull, where to put a thing down).

    Raises:
        ACSGError: an empty id, target or primitive, or an unknown type or state.
    """

    id: str
    type: str
    target: str
    primitive: str
    params: dict[str, Any] = field(default_factory=dict)
    state: str = "unexplored"

    kind: ClassVar[str] = "action"

    def __post_init__(self) -> None:
        if not isinstance(self.id, str) or not self.id:
            raise ACSGError(f"action id: must be a non-empty string, got {self.id!r}")
        if self.type not in ACTION_TYPES:
            raise ACSGError(f"action {self.id}: type {self.type!r} is not one of {ACTION_TYPES}")
        if not isinstance(self.target, str) or not self.target:
            raise ACSGError(f"action {self.id}: target must name an object node, got {self.target!r}")
        if not isinstance(self.primitive, str) or not self.primitive:
            raise ACSGError(f"action {self.id}: primitive must be a non-empty string, got {self.primitive!r}")
        if self.state not in ACTION_STATES:
            raise ACSGError(f"action {self.id}: state {self.state!r} is not one of {ACTION_STATES}")

    @property
    def undo(self) -> str | None:
        """The primitive that puts back what this one changed, if there is one."""
        return UNDO.get(self.primitive)

    def to_dict(self) -> dict[str, Any]:
        """The action's JSON entry.

        Returns:
            A JSON-able dict of every field.
        """
        return {"id": self.id, "kind": "action", "type": self.type, "target": self.target,
                "primitive": self.primitive, "params": dict(self.params), "state": self.state}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ActionNode:
        """Read an action's JSON entry back; params and state may be left out.

        Args:
            data: an entry written by `to_dict`.

        Returns:
            The action node, unexplored unless the entry says otherwise.
        """
        return cls(id=data["id"], type=data["type"], target=data["target"], primitive=data["primitive"],
                   params=dict(data.get("params", {})), state=data.get("state", "unexplored"))


Node = ObjectNode | ActionNode


@dataclass(frozen=True)
class Edge:
    """One edge: ``kind`` is one of `EDGE_KINDS`, ``relation`` what it says (`default_relation`)."""

    source: str
    target: str
    kind: str
    relation: str

    def to_dict(self) -> dict[str, str]:
        """The edge's JSON entry, with the ground truth's field names.

        Returns:
            {"source", "target", "type", "relation"}.
        """
        return {"source": self.source, "target": self.target, "type": self.kind, "relation": self.relation}


def default_relation(kind: str, action_type: str | None = None) -> str | None:
    """The relation an edge gets when none is named, so that callers need name only object-object ones.

    Args:
        kind: the edge's kind.
        action_type: for object-action edges, the action's type.

    Returns:
        "can be opened" and the like, "reveals", "precondition"; None for object-object edges.
    """
    if kind == "object-action":
        return _ACTION_RELATION.get(action_type or "", f"can be {action_type}")
    return {"action-object": "reveals", "action-action": "precondition"}.get(kind)
