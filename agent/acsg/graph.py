"""The action-conditioned scene graph (RoboEXP §III-A) as plain data, and its edits.

An ACSG is a directed acyclic graph of object and action nodes (`agent.acsg.nodes`) joined by the
paper's four kinds of edge. Acyclicity is what makes the graph usable: retrieval walks it in
topological order (`agent.acsg.order`), so a cycle is refused at the edge that would close it,
with the cycle spelt out. Its JSON is `agent.acsg.json_format`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from agent.acsg.nodes import (
    EDGE_KINDS,
    OBJECT_RELATIONS,
    ACSGError,
    ActionNode,
    Edge,
    Node,
    ObjectNode,
    default_relation,
)
from agent.acsg.order import path
from agent.acsg.primitives import action_primitive


class CycleError(ACSGError):
    """An edge that would close a cycle; ``cycle`` lists the node ids around it.

    Args:
        message: what was refused.
        cycle: the node ids around the cycle, the first repeated at the end.
    """

    def __init__(self, message: str, cycle: list[str]) -> None:
        super().__init__(message)
        self.cycle = cycle


class UnknownObjectError(ACSGError):
    """A query that names no object of the graph (or several, ambiguously)."""


class ACSG:
    """The graph: nodes by id in insertion order, edges indexed both ways, kept acyclic.

    Args:
        meta: free facts about the graph (task, seed), kept in its JSON.
    """

    def __init__(self, meta: Mapping[str, Any] | None = None) -> None:
        self.meta: dict[str, Any] = dict(meta or {})
        self._nodes: dict[str, Node] = {}
        self._out: dict[str, dict[str, Edge]] = {}
        self._in: dict[str, dict[str, Edge]] = {}

    # ---- nodes ------------------------------------------------------------------------------
    def add_node(self, node: Node) -> Node:
        """Add a node without edges.

        Args:
            node: an object or action node with an id new to the graph.

        Returns:
            ``node``.

        Raises:
            ACSGError: the id is taken.
        """
        if node.id in self._nodes:
            raise ACSGError(f"node {node.id}: already in the graph")
        self._nodes[node.id] = node
        self._out[node.id], self._in[node.id] = {}, {}
        return node

    def add_object(self, id: str, label: str, **fields: Any) -> ObjectNode:
        """Add an object node.

        Args:
            id: the node id.
            label: what the object is.
            **fields: further fields of `ObjectNode`.

        Returns:
            The new node.
        """
        node = ObjectNode(id, label, **fields)
        self.add_node(node)
        return node

    def add_action(self, id: str, type: str, target: str, primitive: str | None = None, **fields: Any) -> ActionNode:
        """An action on the object ``target``, linked to it by an object-action edge.

        Args:
            id: the node id.
            type: the action's type (`nodes.ACTION_TYPES`).
            target: the id of the object acted on.
            primitive: the skill that does it; by default `primitives.action_primitive`'s.
            **fields: further fields of `ActionNode`.

        Returns:
            The new node.

        Raises:
            ACSGError: ``target`` is no object node of the graph.
        """
        if not isinstance(self._nodes.get(target), ObjectNode):
            raise ACSGError(f"action {id}: target {target!r} is not an object node of the graph")
        if primitive is None:
            primitive = action_primitive(type, self._nodes[target].label)
        node = ActionNode(id, type, target, primitive, **fields)
        self.add_node(node)
        self.add_edge(target, id)
        return node

    def remove_action(self, action_id: str) -> None:
        """Take an action out of the graph with its edges: one proposed and never run on a thing
        found to be another already in the graph.

        Args:
            action_id: the action node's id.

        Raises:
            ACSGError: it is no action node.
        """
        self.action(action_id)
        for source in list(self._in[action_id]):
            self._out[source].pop(action_id, None)
        for target in list(self._out[action_id]):
            self._in[target].pop(action_id, None)
        del self._nodes[action_id], self._out[action_id], self._in[action_id]

    def merge_objects(self, keep: str, other: str) -> None:
        """Declare the object ``other`` the same thing as ``keep``: its edges go over to ``keep``
        (those ``keep`` has already, or that would close a cycle, are dropped) and it leaves the graph.

        Args:
            keep: the object that stays.
            other: the object folded into it.

        Raises:
            ACSGError: either is no object node, or an action acts on ``other`` (the action
                names its target, and moving it is the caller's decision).
        """
        self.object(keep)
        self.object(other)
        if keep == other:
            return
        acted = [t for t, e in self._out[other].items() if e.kind == "object-action"]
        if acted:
            raise ACSGError(f"merge {other} into {keep}: {', '.join(acted)} act on {other}")
        moved = [(s, keep, e) for s, e in self._in[other].items()] + [(keep, t, e) for t, e in self._out[other].items()]
        for source, target in [(s, other) for s in self._in[other]] + [(other, t) for t in self._out[other]]:
            self._out[source].pop(target, None)
            self._in[target].pop(source, None)
        del self._nodes[other], self._out[other], self._in[other]
        for source, target, edge in moved:
            if source == target or self.edge(source, target) is not None:
                continue  # keep's own account stands
            try:
                self.add_edge(source, target, edge.kind, edge.relation)
            except ACSGError:  # a cycle through keep
                continue

    def node(self, node_id: str) -> Node:
        """The node with an id.

        Args:
            node_id: the id.

        Returns:
            The node.

        Raises:
            ACSGError: no such node.
        """
        try:
            return self._nodes[node_id]
        except KeyError:
            raise ACSGError(f"node {node_id!r}: not in the graph") from None

    def object(self, node_id: str) -> ObjectNode:
        """The object node with an id.

        Args:
            node_id: the id.

        Returns:
            The node.

        Raises:
            ACSGError: no such node, or it is an action.
        """
        node = self.node(node_id)
        if not isinstance(node, ObjectNode):
            raise ACSGError(f"node {node_id!r}: is an action, not an object")
        return node

    def action(self, node_id: str) -> ActionNode:
        """The action node with an id.

        Args:
            node_id: the id.

        Returns:
            The node.

        Raises:
            ACSGError: no such node, or it is an object.
        """
        node = self.node(node_id)
        if not isinstance(node, ActionNode):
            raise ACSGError(f"node {node_id!r}: is an object, not an action")
        return node

    def __contains__(self, node_id: object) -> bool:
        return node_id in self._nodes

    def __len__(self) -> int:
        return len(self._nodes)

    def nodes(self) -> list[Node]:
        """Every node, in insertion order.

        Returns:
            The nodes.
        """
        return list(self._nodes.values())

    def objects(self) -> list[ObjectNode]:
        """The object nodes, in insertion order.

        Returns:
            The object nodes.
        """
        return [n for n in self._nodes.values() if isinstance(n, ObjectNode)]

    def actions(self) -> list[ActionNode]:
        """The action nodes, in insertion order.

        Returns:
            The action nodes.
        """
        return [n for n in self._nodes.values() if isinstance(n, ActionNode)]

    # ---- edges ------------------------------------------------------------------------------
    def add_edge(self, source: str, target: str, kind: str | None = None, relation: str | None = None) -> Edge:
        """Add (or find again) the edge ``source`` -> ``target``.

        Adding the same edge twice returns the first; a different edge between the same two
        nodes, or one that closes a cycle, is refused.

        Args:
            source: the id the edge leaves.
            target: the id it enters.
            kind: one of `nodes.EDGE_KINDS`; follows from the two nodes when not given.
            relation: what the edge says; defaults for every kind but object-object.

        Returns:
            The edge in the graph.

        Raises:
            ACSGError: an unknown node, a kind or relation that does not fit, or a clash with the
                edge already there.
            CycleError: the edge would close a cycle.
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
        back = path(self, target, source)
        if back is not None:
            cycle = [source, *back]
            raise CycleError(f"edge {source}->{target}: would close the cycle {' -> '.join(cycle)}", cycle)
        self._out[source][target] = edge
        self._in[target][source] = edge
        return edge

    def edges(self, kind: str | None = None) -> list[Edge]:
        """The edges, by source in insertion order.

        Args:
            kind: keep only edges of this kind (all when None).

        Returns:
            The edges.
        """
        return [e for out in self._out.values() for e in out.values() if kind is None or e.kind == kind]

    def edge(self, source: str, target: str) -> Edge | None:
        """The edge ``source`` -> ``target``, or None when there is none.

        Args:
            source: the edge's source node id.
            target: its target node id.

        Returns:
            The edge, or None.
        """
        return self._out.get(source, {}).get(target)

    def successors(self, node_id: str, kind: str | None = None) -> list[str]:
        """The ids a node's edges lead to, in the order the edges were added.

        Args:
            node_id: the node.
            kind: keep only edges of this kind (all when None).

        Returns:
            The target ids.
        """
        return [t for t, e in self._out[self.node(node_id).id].items() if kind is None or e.kind == kind]

    def predecessors(self, node_id: str, kind: str | None = None) -> list[str]:
        """The ids whose edges lead to a node, in the order the edges were added.

        Args:
            node_id: the node.
            kind: keep only edges of this kind (all when None).

        Returns:
            The source ids.
        """
        return [s for s, e in self._in[self.node(node_id).id].items() if kind is None or e.kind == kind]

    def parent(self, object_id: str) -> tuple[str, str] | None:
        """Where an object sits in the scene: what it belongs to, stands on or lies in.

        Args:
            object_id: the object.

        Returns:
            (parent id, relation) of its first object-object in-edge, or None for a root.
        """
        for source, edge in self._in[self.node(object_id).id].items():
            if edge.kind == "object-object":
                return source, edge.relation
        return None

    # ---- lookup -----------------------------------------------------------------------------
    def find_object(self, query: str) -> ObjectNode:
        """The object a person means by ``query``.

        Args:
            query: a node id ("o7"), an instance id ("7"), a label ("apple") or colour and label
                ("red apple").

        Returns:
            The one object it names.

        Raises:
            UnknownObjectError: no object, or several, match; the text lists what would have.
        """
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
