"""The action-conditioned scene graph (RoboEXP §III-A) as plain data.

An ACSG is a directed acyclic graph of object nodes (what is there: semantics and geometry) and
action nodes (what can be done: a high-level type and the low-level primitive that does it).
Edges come in the paper's four kinds, named as in the ground truth of `worlds.tabletop_scene`:

- ``object-object``: parent to child, naming the child's relation to it (belongs, on, inside, under);
- ``object-action``: the object can be acted on ("can be opened", "can be picked");
- ``action-object``: the action reveals the object (one level deep: what it makes visible);
- ``action-action``: precondition (move the condiment away before opening the door).

Acyclicity is what makes the graph usable: retrieval walks it in topological order, so a cycle
is refused at the edge that would close it, with the cycle spelt out. The JSON written here
(`FORMAT`, `VERSION`) keeps the ground truth's edge fields, so the two read alike; the ground
truth itself converts with `from_ground_truth`, and `from_dict` takes either.
"""

from __future__ import annotations

import heapq
import json
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

FORMAT = "homebot.acsg"
VERSION = 1

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
#: The paper's seven primitives (App. I-D); the names the executor is asked to run.
PRIMITIVES = ("open_door", "close_door", "open_drawer", "close_drawer", "pick_away", "pick_back", "move_camera")
#: What undoes a primitive, so exploration can leave the scene as it found it. ``open`` and
#: ``close`` stand for parts that are neither door nor drawer (a lid, a flap).
UNDO = {"open_door": "close_door", "open_drawer": "close_drawer", "open": "close", "pick_away": "pick_back"}
_ACTION_RELATION = {"open": "can be opened", "pick": "can be picked"}


class ACSGError(ValueError):
    """A graph, node or edge that breaks the ACSG's rules; the text names the field."""


class CycleError(ACSGError):
    """An edge that would close a cycle; ``cycle`` lists the node ids around it."""

    def __init__(self, message: str, cycle: list[str]) -> None:
        super().__init__(message)
        self.cycle = cycle


class UnknownObjectError(ACSGError):
    """A query that names no object of the graph (or several, ambiguously)."""


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
    """

    id: str
    label: str
    instance: str | None = None
    attributes: dict[str, Any] = field(default_factory=dict)
    points: np.ndarray | None = None  # (N, 3) world points
    centroid: np.ndarray | None = None  # (3,)
    extent: np.ndarray | None = None  # (3,) full size of the axis-aligned box
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
        colour = self.attributes.get("colour")
        return f"{colour} {self.label}" if colour else self.label

    def to_dict(self) -> dict[str, Any]:
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
        return cls(
            id=data["id"], label=data["label"], instance=data.get("instance"),
            attributes=dict(data.get("attributes", {})), points=data.get("points"),
            centroid=data.get("centroid"), extent=data.get("extent"), explored=bool(data.get("explored", False)),
        )


@dataclass(eq=False)
class ActionNode:
    """a_k = (a_k, T_k): the high-level ``type`` on the object ``target`` and the low-level
    ``primitive`` with its ``params`` (which handle to pull, where to put a thing down)."""

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
        return {"id": self.id, "kind": "action", "type": self.type, "target": self.target,
                "primitive": self.primitive, "params": dict(self.params), "state": self.state}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ActionNode:
        return cls(id=data["id"], type=data["type"], target=data["target"], primitive=data["primitive"],
                   params=dict(data.get("params", {})), state=data.get("state", "unexplored"))


Node = ObjectNode | ActionNode


@dataclass(frozen=True)
class Edge:
    source: str
    target: str
    kind: str  # one of EDGE_KINDS
    relation: str

    def to_dict(self) -> dict[str, str]:
        return {"source": self.source, "target": self.target, "type": self.kind, "relation": self.relation}


def default_relation(kind: str, action_type: str | None = None) -> str | None:
    """The relation an edge of ``kind`` gets when none is named (object-object edges must name theirs)."""
    if kind == "object-action":
        return _ACTION_RELATION.get(action_type or "", f"can be {action_type}")
    return {"action-object": "reveals", "action-action": "precondition"}.get(kind)


def open_primitive(part_label: str) -> str:
    """The primitive that opens a part: doors and drawers have their own, anything else ``open``."""
    return f"open_{part_label}" if part_label in ("door", "drawer") else "open"


class ACSG:
    """The graph: nodes by id in insertion order, edges indexed both ways, kept acyclic."""

    def __init__(self, meta: Mapping[str, Any] | None = None) -> None:
        self.meta: dict[str, Any] = dict(meta or {})
        self._nodes: dict[str, Node] = {}
        self._out: dict[str, dict[str, Edge]] = {}
        self._in: dict[str, dict[str, Edge]] = {}

    # ---- nodes ------------------------------------------------------------------------------
    def add_node(self, node: Node) -> Node:
        if node.id in self._nodes:
            raise ACSGError(f"node {node.id}: already in the graph")
        self._nodes[node.id] = node
        self._out[node.id], self._in[node.id] = {}, {}
        return node

    def add_object(self, id: str, label: str, **fields: Any) -> ObjectNode:
        node = ObjectNode(id, label, **fields)
        self.add_node(node)
        return node

    def add_action(self, id: str, type: str, target: str, primitive: str | None = None, **fields: Any) -> ActionNode:
        """An action on the object ``target``, linked to it by an object-action edge."""
        if not isinstance(self._nodes.get(target), ObjectNode):
            raise ACSGError(f"action {id}: target {target!r} is not an object node of the graph")
        if primitive is None:
            primitive = {"open": open_primitive(self._nodes[target].label), "pick": "pick_away"}.get(type, type)
        node = ActionNode(id, type, target, primitive, **fields)
        self.add_node(node)
        self.add_edge(target, id)
        return node

    def node(self, node_id: str) -> Node:
        try:
            return self._nodes[node_id]
        except KeyError:
            raise ACSGError(f"node {node_id!r}: not in the graph") from None

    def object(self, node_id: str) -> ObjectNode:
        node = self.node(node_id)
        if not isinstance(node, ObjectNode):
            raise ACSGError(f"node {node_id!r}: is an action, not an object")
        return node

    def action(self, node_id: str) -> ActionNode:
        node = self.node(node_id)
        if not isinstance(node, ActionNode):
            raise ACSGError(f"node {node_id!r}: is an object, not an action")
        return node

    def __contains__(self, node_id: object) -> bool:
        return node_id in self._nodes

    def __len__(self) -> int:
        return len(self._nodes)

    def nodes(self) -> list[Node]:
        return list(self._nodes.values())

    def objects(self) -> list[ObjectNode]:
        return [n for n in self._nodes.values() if isinstance(n, ObjectNode)]

    def actions(self) -> list[ActionNode]:
        return [n for n in self._nodes.values() if isinstance(n, ActionNode)]

    # ---- edges ------------------------------------------------------------------------------
    def add_edge(self, source: str, target: str, kind: str | None = None, relation: str | None = None) -> Edge:
        """Add (or find again) the edge ``source`` -> ``target``.

        ``kind`` follows from the two nodes when not given; ``relation`` defaults for every kind but
        object-object. Adding the same edge twice returns the first; a different edge between the
        same two nodes, or one that closes a cycle, is refused.
        """
        src, dst = self.node(source), self.node(target)
        inferred = f"{src.kind}-{dst.kind}"
        kind = kind or inferred
        if kind not in EDGE_KINDS:
            raise ACSGError(f"edge {source}->{target}: kind {kind!r} is not one of {tuple(EDGE_KINDS)}")
        if kind != inferred:
            raise ACSGError(f"edge {source}->{target}: kind {kind!r} joins a {src.kind} to a {dst.kind}")
        if relation is None:
            relation = default_relation(kind, dst.type if isinstance(dst, ActionNode) else None)
        if kind == "object-object" and relation not in OBJECT_RELATIONS:
            raise ACSGError(f"edge {source}->{target}: relation {relation!r} is not one of {OBJECT_RELATIONS}")
        if not relation:
            raise ACSGError(f"edge {source}->{target}: relation must be a non-empty string")
        edge = Edge(source, target, kind, relation)
        existing = self._out[source].get(target)
        if existing is not None:
            if existing != edge:
                raise ACSGError(f"edge {source}->{target}: already there as {existing.kind} {existing.relation!r}, "
                                f"not {kind} {relation!r}")
            return existing
        if source == target:
            raise CycleError(f"edge {source}->{target}: a node cannot point to itself", [source, source])
        back = self.path(target, source)
        if back is not None:
            cycle = [source, *back]
            raise CycleError(f"edge {source}->{target}: would close the cycle {' -> '.join(cycle)}", cycle)
        self._out[source][target] = edge
        self._in[target][source] = edge
        return edge

    def edges(self, kind: str | None = None) -> list[Edge]:
        return [e for out in self._out.values() for e in out.values() if kind is None or e.kind == kind]

    def edge(self, source: str, target: str) -> Edge | None:
        return self._out.get(source, {}).get(target)

    def successors(self, node_id: str, kind: str | None = None) -> list[str]:
        return [t for t, e in self._out[self.node(node_id).id].items() if kind is None or e.kind == kind]

    def predecessors(self, node_id: str, kind: str | None = None) -> list[str]:
        return [s for s, e in self._in[self.node(node_id).id].items() if kind is None or e.kind == kind]

    def parent(self, object_id: str) -> tuple[str, str] | None:
        """(parent id, relation) of an object's first object-object in-edge, or None for a root."""
        for source, edge in self._in[self.node(object_id).id].items():
            if edge.kind == "object-object":
                return source, edge.relation
        return None

    def actions_on(self, object_id: str) -> list[ActionNode]:
        return [self.action(a) for a in self.successors(object_id, "object-action")]

    def path(self, source: str, target: str) -> list[str] | None:
        """Some directed path from ``source`` to ``target`` (both included), or None."""
        stack, came = [source], {source: source}
        while stack:
            here = stack.pop()
            if here == target:
                path = [here]
                while path[-1] != source:
                    path.append(came[path[-1]])
                return path[::-1]
            for nxt in self._out[here]:
                if nxt not in came:
                    came[nxt] = here
                    stack.append(nxt)
        return None

    def ancestors(self, node_id: str) -> set[str]:
        seen: set[str] = set()
        stack = [self.node(node_id).id]
        while stack:
            for source in self._in[stack.pop()]:
                if source not in seen:
                    seen.add(source)
                    stack.append(source)
        return seen

    def roots(self) -> list[str]:
        return [n for n in self._nodes if not self._in[n]]

    def topological_order(self, among: Iterable[str] | None = None) -> list[str]:
        """Every node (or those of ``among``) after all its predecessors; ties go by insertion order."""
        rank = {n: i for i, n in enumerate(self._nodes)}
        indegree = {n: len(self._in[n]) for n in self._nodes}
        heap = [(rank[n], n) for n, d in indegree.items() if d == 0]
        heapq.heapify(heap)
        order = []
        while heap:
            _, here = heapq.heappop(heap)
            order.append(here)
            for nxt in self._out[here]:
                indegree[nxt] -= 1
                if indegree[nxt] == 0:
                    heapq.heappush(heap, (rank[nxt], nxt))
        if among is None:
            return order
        keep = set(among)
        return [n for n in order if n in keep]

    def depths(self) -> dict[str, int]:
        """Longest-path depth of every node from a root: the layers of a top-down drawing."""
        depth: dict[str, int] = {}
        for n in self.topological_order():
            depth[n] = max((depth[p] + 1 for p in self._in[n]), default=0)
        return depth

    # ---- lookup -----------------------------------------------------------------------------
    def find_object(self, query: str) -> ObjectNode:
        """The object a person means by ``query``: a node id ("o7"), an instance id ("7"), a label
        ("apple") or colour and label ("red apple"). Unknown or ambiguous queries raise, listing
        what would have matched."""
        query = str(query).strip()
        if isinstance(self._nodes.get(query), ObjectNode):
            return self._nodes[query]  # type: ignore[return-value]
        objects = self.objects()
        by_instance = [o for o in objects if o.instance == query]
        if len(by_instance) == 1:
            return by_instance[0]
        wanted = query.lower()
        matches = [o for o in objects if o.label.lower() == wanted] or [
            o for o in objects if o.describe().lower() == wanted]
        if len(matches) == 1:
            return matches[0]
        if matches:
            options = ", ".join(f"{o.id} ({o.describe()})" for o in matches)
            raise UnknownObjectError(f"object {query!r}: ambiguous, it could be {options}; name one by id")
        known = ", ".join(sorted({o.label for o in objects}))
        raise UnknownObjectError(f"object {query!r}: no such object in the graph; labels are: {known}")

    # ---- JSON -------------------------------------------------------------------------------
    def to_dict(self) -> dict[str, Any]:
        return {"format": FORMAT, "version": VERSION, "meta": dict(self.meta),
                "nodes": [n.to_dict() for n in self._nodes.values()],
                "edges": [e.to_dict() for e in self.edges()]}

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> ACSG:
        """Read our format, a ground-truth ACSG (`worlds.tabletop_scene`), or a suite record holding one."""
        if not isinstance(data, Mapping):
            raise ACSGError(f"acsg: expected a JSON object, got {type(data).__name__}")
        if "format" not in data:
            if "acsg" in data:
                return cls.from_dict(data["acsg"])
            if "nodes" in data and "edges" in data:
                return from_ground_truth(data)
            raise ACSGError("acsg: neither our format (no 'format' field) nor a ground-truth graph (no 'nodes')")
        if data["format"] != FORMAT:
            raise ACSGError(f"acsg format: {data['format']!r} is not {FORMAT!r}")
        if not isinstance(data.get("version"), int) or not 1 <= data["version"] <= VERSION:
            raise ACSGError(f"acsg version: {data.get('version')!r}; this reader knows versions 1 to {VERSION}")
        graph = cls(data.get("meta"))
        for index, entry in enumerate(data.get("nodes", [])):
            kind = entry.get("kind")
            if kind == "object":
                graph.add_node(ObjectNode.from_dict(entry))
            elif kind == "action":
                graph.add_node(ActionNode.from_dict(entry))
            else:
                raise ACSGError(f"nodes[{index}].kind: {kind!r} is neither 'object' nor 'action'")
        for index, entry in enumerate(data.get("edges", [])):
            try:
                graph.add_edge(entry["source"], entry["target"], entry.get("type"), entry.get("relation"))
            except KeyError as missing:
                raise ACSGError(f"edges[{index}]: missing field {missing}") from None
        for action in graph.actions():
            if action.target not in graph:
                raise ACSGError(f"action {action.id}: target {action.target!r} is not in the graph")
        return graph

    def to_json(self, indent: int | None = 2) -> str:
        return json.dumps(self.to_dict(), indent=indent)

    @classmethod
    def from_json(cls, text: str) -> ACSG:
        return cls.from_dict(json.loads(text))

    def save(self, path: Path | str) -> Path:
        path = Path(path)
        path.write_text(self.to_json() + "\n")
        return path

    def __iter__(self) -> Iterator[Node]:
        return iter(self._nodes.values())


def from_ground_truth(data: Mapping[str, Any]) -> ACSG:
    """The ground-truth JSON of `TabletopScene.ground_truth_acsg` as an `ACSG`.

    Object labels are the categories (colour goes to the attributes); every node counts as
    explored, since the ground truth is what a finished exploration should hold.
    """
    graph = ACSG({key: data[key] for key in ("task", "seed") if key in data})
    nodes = data.get("nodes")
    if not isinstance(nodes, list):
        raise ACSGError("ground truth: 'nodes' must be a list")
    for index, entry in enumerate(nodes):
        try:
            if entry["kind"] == "object":
                attributes = {k: entry[k] for k in ("colour",) if k in entry}
                graph.add_object(entry["id"], entry["category"], instance=entry.get("instance"),
                                 attributes=attributes, explored=True)
        except KeyError as missing:
            raise ACSGError(f"ground truth nodes[{index}]: missing field {missing}") from None
    for index, entry in enumerate(nodes):
        if entry["kind"] == "action":
            try:
                target = graph.object(entry["target"])
                primitive = open_primitive(target.label) if entry["type"] == "open" else "pick_away"
                params = {k: entry[k] for k in ("handle",) if k in entry}
                graph.add_node(ActionNode(entry["id"], entry["type"], target.id, primitive, params, "explored"))
            except KeyError as missing:
                raise ACSGError(f"ground truth nodes[{index}]: missing field {missing}") from None
        elif entry["kind"] != "object":
            raise ACSGError(f"ground truth nodes[{index}].kind: {entry['kind']!r} is neither 'object' nor 'action'")
    for index, entry in enumerate(data.get("edges", [])):
        try:
            graph.add_edge(entry["source"], entry["target"], entry["type"], entry["relation"])
        except KeyError as missing:
            raise ACSGError(f"ground truth edges[{index}]: missing field {missing}") from None
    return graph


def load_acsg(path: Path | str, seed: int | None = None) -> ACSG:
    """An ACSG from a file: our JSON, a ground-truth graph, a suite record, or a suite's JSON lines
    (``seed`` picks the record; without it the file must hold one)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise ACSGError(f"{path}: cannot read ({error.strerror})") from None
    if path.suffix == ".jsonl":
        records = [json.loads(line) for line in text.splitlines() if line.strip()]
        if seed is not None:
            records = [r for r in records if r.get("seed") == seed]
        if len(records) != 1:
            which = f"seed {seed}" if seed is not None else "one record (pass a seed)"
            raise ACSGError(f"{path}: expected {which}, found {len(records)} records")
        return ACSG.from_dict(records[0])
    try:
        data = json.loads(text)
    except json.JSONDecodeError as error:
        raise ACSGError(f"{path}: not JSON ({error.msg} at line {error.lineno})") from None
    return ACSG.from_dict(data)
