"""Walking an ACSG's edges: paths, ancestors, topological order and depth.

Retrieval plans in topological order (`agent.acsg.plan`), a drawing lays nodes out by depth
(`agent.acsg.draw`), and the graph looks for a path back before adding an edge, to refuse cycles.
Ties between nodes go by insertion order, so every walk is deterministic.
"""

from __future__ import annotations

import heapq
from collections.abc import Iterable
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from agent.acsg.graph import ACSG


def path(graph: ACSG, source: str, target: str) -> list[str] | None:
    """Some directed path between two nodes: the cycle an edge back would close.

    Args:
        graph: the graph.
        source: where the path starts.
        target: where it ends.

    Returns:
        The node ids from ``source`` to ``target`` (both included), or None when there is none.
    """
    stack, came = [source], {source: source}
    while stack:
        here = stack.pop()
        if here == target:
            found = [here]
            while found[-1] != source:
                found.append(came[found[-1]])
            return found[::-1]
        for nxt in graph.successors(here):
            if nxt not in came:
                came[nxt] = here
                stack.append(nxt)
    return None


def ancestors(graph: ACSG, node_id: str) -> set[str]:
    """Every node a node can be reached from: what must happen before it.

    Args:
        graph: the graph.
        node_id: the node.

    Returns:
        The ids of all nodes with a path to ``node_id`` (not itself).
    """
    seen: set[str] = set()
    stack = [graph.node(node_id).id]
    while stack:
        for source in graph.predecessors(stack.pop()):
            if source not in seen:
                seen.add(source)
                stack.append(source)
    return seen


def topological_order(graph: ACSG, among: Iterable[str] | None = None) -> list[str]:
    """The nodes in an order that does each after all its predecessors.

    Args:
        graph: the graph.
        among: keep only these node ids (all when None).

    Returns:
        Node ids, each after all its predecessors; ties go by insertion order.
    """
    ids = [n.id for n in graph.nodes()]
    rank = {n: i for i, n in enumerate(ids)}
    indegree = {n: len(graph.predecessors(n)) for n in ids}
    heap = [(rank[n], n) for n, d in indegree.items() if d == 0]
    heapq.heapify(heap)
    order = []
    while heap:
        _, here = heapq.heappop(heap)
        order.append(here)
        for nxt in graph.successors(here):
            indegree[nxt] -= 1
            if indegree[nxt] == 0:
                heapq.heappush(heap, (rank[nxt], nxt))
    if among is None:
        return order
    keep = set(among)
    return [n for n in order if n in keep]


def depths(graph: ACSG) -> dict[str, int]:
    """Each node's layer in a top-down drawing.

    Args:
        graph: the graph.

    Returns:
        Node id -> the length of the longest path to it from a root.
    """
    depth: dict[str, int] = {}
    for n in topological_order(graph):
        depth[n] = max((depth[p] + 1 for p in graph.predecessors(n)), default=0)
    return depth
