"""RoboEXP's Table I metrics on plain data.

- Success: the explored ACSG equals the ground truth, i.e. their graph edit distance is 0
  (same objects, actions and relations, under some matching of the nodes).
- Object recovery (the paper's): the share of hidden objects (those some action reveals in the
  ground truth) that the exploration found. `position_recovery` is the other reading, the share
  of things back at their start place within a tolerance.
- State recovery: the paper's is binary, the scene as it was before exploring (`scene_restored`:
  every thing back in place and every part back in its state); `state_recovery` is the share of
  articulated parts back in their start state.
- Unexplored space: the share of the need-to-explore space never looked into. Need-to-explore
  is read off the ground truth: every open action (an empty drawer still has to be opened) and
  every pick that reveals something (a box over a doll; not an obstacle moved aside).
- Graph edit distance: node and edge insertions, deletions and substitutions at cost 1 each.
  Nodes match on kind and label (an object's category, an action's type), edges on kind and
  relation. networkx finds the optimum; the distance under the identity matching of node ids
  (the ids the perception gave) is an upper bound that is often exact and always cheap, so it
  bounds the search, and a zero there needs no search at all.
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from agent.acsg.graph import ACSG
from agent.acsg.nodes import ActionNode, ObjectNode


def node_label(node: ObjectNode | ActionNode) -> str:
    """What a node is compared by: an object's label, an action's type.

    Args:
        node: the node.

    Returns:
        The label or type.
    """
    return node.type if isinstance(node, ActionNode) else node.label


def to_networkx(graph: ACSG) -> Any:
    """The graph as an ``nx.DiGraph`` with ``kind`` and ``label`` on nodes, ``kind`` and ``relation`` on edges.

    Args:
        graph: the graph.

    Returns:
        The ``nx.DiGraph``.
    """
    import networkx as nx

    out = nx.DiGraph()
    for node in graph.nodes():
        out.add_node(node.id, kind=node.kind, label=node_label(node))
    for edge in graph.edges():
        out.add_edge(edge.source, edge.target, kind=edge.kind, relation=edge.relation)
    return out


def _node_match(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    return a["kind"] == b["kind"] and a["label"] == b["label"]


def _edge_match(a: Mapping[str, Any], b: Mapping[str, Any]) -> bool:
    return a["kind"] == b["kind"] and a["relation"] == b["relation"]


def aligned_edit_distance(a: ACSG, b: ACSG) -> int:
    """Edit cost when node ids are taken as the matching: an upper bound on the true distance.

    Args:
        a: one graph.
        b: the other.

    Returns:
        The cost.
    """
    cost = 0
    ids_a, ids_b = {n.id: n for n in a.nodes()}, {n.id: n for n in b.nodes()}
    for node_id in ids_a.keys() | ids_b.keys():
        x, y = ids_a.get(node_id), ids_b.get(node_id)
        if x is None or y is None:
            cost += 1
        elif x.kind != y.kind or node_label(x) != node_label(y):
            cost += 1
    edges_a = {(e.source, e.target): e for e in a.edges()}
    edges_b = {(e.source, e.target): e for e in b.edges()}
    for key in edges_a.keys() | edges_b.keys():
        x, y = edges_a.get(key), edges_b.get(key)
        if x is None or y is None:
            cost += 1
        elif x.kind != y.kind or x.relation != y.relation:
            cost += 1
    return cost


@dataclass(frozen=True)
class EditDistance:
    value: float
    exact: bool  # False: the search ran out of time; value is the best found (an upper bound)


def edit_distance(explored: ACSG, truth: ACSG, timeout_s: float = 10.0) -> EditDistance:
    """The graph edit distance, bounded by the id-aligned cost; see the module docstring.

    Args:
        explored: the explored graph.
        truth: the ground truth.
        timeout_s: how long the exact search may take.

    Returns:
        The distance, and whether it is exact.
    """
    bound = aligned_edit_distance(explored, truth)
    if bound == 0:
        return EditDistance(0.0, True)
    import networkx as nx

    started = time.monotonic()
    found = nx.graph_edit_distance(to_networkx(explored), to_networkx(truth), node_match=_node_match,
                                   edge_match=_edge_match, upper_bound=bound, timeout=timeout_s)
    finished = time.monotonic() - started < timeout_s
    value = bound if found is None else min(float(found), float(bound))
    return EditDistance(float(value), finished)


def graph_edit_distance(explored: ACSG, truth: ACSG, timeout_s: float = 10.0) -> float:
    """The value of `edit_distance`.

    Args:
        explored: the explored graph.
        truth: the ground truth.
        timeout_s: how long the exact search may take.

    Returns:
        The distance.
    """
    return edit_distance(explored, truth, timeout_s).value


def is_success(explored: ACSG, truth: ACSG) -> bool:
    """Whether the graphs are the same up to node ids: an isomorphism keeping labels and relations.

    Args:
        explored: the explored graph.
        truth: the ground truth.

    Returns:
        Whether they are.
    """
    if aligned_edit_distance(explored, truth) == 0:
        return True
    import networkx as nx

    return bool(nx.is_isomorphic(to_networkx(explored), to_networkx(truth), node_match=_node_match,
                                 edge_match=_edge_match))


def hidden_objects(graph: ACSG) -> list[str]:
    """Objects some action reveals: what cannot be seen without acting.

    Args:
        graph: the graph.

    Returns:
        Their node ids.
    """
    return [n.id for n in graph.objects() if graph.predecessors(n.id, "action-object")]


def object_recovery(explored: ACSG, truth: ACSG, by: str = "label") -> float:
    """Share of the ground truth's hidden objects found by the exploration (1.0 when none are hidden).

    ``by="label"`` counts matching labels among the objects the exploration found by acting (the
    ids of a real perception are its own); ``by="id"`` asks for the same node id and label.

    Args:
        explored: the explored graph.
        truth: the ground truth.
        by: "label" or "id".

    Returns:
        The share.
    """
    hidden = [truth.object(n) for n in hidden_objects(truth)]
    if not hidden:
        return 1.0
    if by == "id":
        found = sum(1 for o in hidden if o.id in explored and node_label(explored.node(o.id)) == o.label)
    elif by == "label":
        wanted = Counter(o.label for o in hidden)
        got = Counter(explored.object(n).label for n in hidden_objects(explored))
        found = sum(min(count, got[label]) for label, count in wanted.items())
    else:
        raise ValueError(f"by: {by!r} is neither 'label' nor 'id'")
    return found / len(hidden)


def position_recovery(start: Mapping[str, Any], final: Mapping[str, Any], tolerance_m: float = 0.01) -> float:
    """Share of things (keys of ``start``) whose final position is within ``tolerance_m`` of the start;
    a thing missing from ``final`` is not recovered. 1.0 for no things.

    Args:
        start: each thing's start position.
        final: each thing's final position.
        tolerance_m: how far from the start counts as back.

    Returns:
        The share.
    """
    if not start:
        return 1.0
    back = 0
    for key, where in start.items():
        if key in final:
            back += float(np.linalg.norm(np.asarray(final[key], float) - np.asarray(where, float))) <= tolerance_m
    return back / len(start)


def state_recovery(start: Mapping[str, float], final: Mapping[str, float], tolerance: float = 1e-3) -> float:
    """Share of articulated parts (keys of ``start``: joint values or 0/1 states) back in their start state.

    Args:
        start: each part's start state.
        final: each part's final state.
        tolerance: how far from the start counts as back.

    Returns:
        The share.
    """
    if not start:
        return 1.0
    back = sum(1 for key, value in start.items() if key in final and abs(final[key] - value) <= tolerance)
    return back / len(start)


def scene_restored(start_positions: Mapping[str, Any], final_positions: Mapping[str, Any],
                   start_states: Mapping[str, float], final_states: Mapping[str, float],
                   tolerance_m: float = 0.01, tolerance: float = 1e-3) -> bool:
    """The paper's binary State Recovery: every thing back in place and every part in its state.

    Args:
        start_positions: each thing's start position.
        final_positions: each thing's final position.
        start_states: each part's start state.
        final_states: each part's final state.
        tolerance_m: how far from its start a thing may be.
        tolerance: how far from its start a part's state may be.

    Returns:
        Whether the scene is restored.
    """
    return (position_recovery(start_positions, final_positions, tolerance_m) == 1.0
            and state_recovery(start_states, final_states, tolerance) == 1.0)


def need_to_explore(truth: ACSG) -> list[str]:
    """Action ids of the ground truth's need-to-explore space: every open, every revealing pick.

    Args:
        truth: the ground truth.

    Returns:
        The action ids.
    """
    return [a.id for a in truth.actions()
            if a.type == "open" or (a.type == "pick" and truth.successors(a.id, "action-object"))]


def unexplored_space(truth: ACSG, explored: ACSG | Iterable[str]) -> float:
    """Share of the need-to-explore space never explored. ``explored`` is the explored graph (its
    actions in state "explored" count) or the ids of the actions carried out.

    Args:
        truth: the ground truth.
        explored: the explored graph, or the ids of the actions carried out.

    Returns:
        The share.
    """
    needed = need_to_explore(truth)
    if not needed:
        return 0.0
    if isinstance(explored, ACSG):
        done = {a.id for a in explored.actions() if a.state == "explored"}
    else:
        done = set(explored)
    return sum(1 for a in needed if a not in done) / len(needed)


@dataclass(frozen=True)
class EpisodeMetrics:
    success: bool
    object_recovery: float
    state_recovered: bool
    position_recovery: float
    state_recovery: float
    unexplored_space: float
    graph_edit_distance: float
    ged_exact: bool

    def as_dict(self) -> dict[str, Any]:
        """The metrics as a plain dict, for result files.

        Returns:
            The dict.
        """
        return dict(vars(self))


def episode_metrics(explored: ACSG, truth: ACSG, start_positions: Mapping[str, Any],
                    final_positions: Mapping[str, Any], start_states: Mapping[str, float],
                    final_states: Mapping[str, float], timeout_s: float = 10.0,
                    tolerance_m: float = 0.01) -> EpisodeMetrics:
    """Every Table I metric of one exploration; a thing within ``tolerance_m`` of its start is back.

    Args:
        explored: the explored graph.
        truth: the ground truth.
        start_positions: each thing's start position.
        final_positions: each thing's final position.
        start_states: each part's start state.
        final_states: each part's final state.
        timeout_s: how long the exact edit distance may take.
        tolerance_m: how far from its start a thing may be.

    Returns:
        The metrics.
    """
    ged = edit_distance(explored, truth, timeout_s)
    return EpisodeMetrics(
        success=ged.value == 0.0 or is_success(explored, truth),
        object_recovery=object_recovery(explored, truth),
        state_recovered=scene_restored(start_positions, final_positions, start_states, final_states, tolerance_m),
        position_recovery=position_recovery(start_positions, final_positions, tolerance_m),
        state_recovery=state_recovery(start_states, final_states),
        unexplored_space=unexplored_space(truth, explored),
        graph_edit_distance=ged.value,
        ged_exact=ged.exact,
    )


def mean_and_sem(values: Iterable[float]) -> tuple[float, float]:
    """Mean and standard error of the mean, as Table I reports them (± over the variants).

    Args:
        values: the values.

    Returns:
        The mean and its standard error (0 for one value).

    Raises:
        ValueError: no values.
    """
    data = [float(v) for v in values]
    if not data:
        raise ValueError("mean_and_sem: no values")
    mean = sum(data) / len(data)
    if len(data) == 1:
        return mean, 0.0
    var = sum((v - mean) ** 2 for v in data) / (len(data) - 1)
    return mean, math.sqrt(var / len(data))
