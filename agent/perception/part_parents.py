"""Which remembered instance a part belongs to: handles to doors and drawers, those to storage.

The labels say only what kind of thing a part is, not whose it is, so the parent is the instance of
an allowed category (`MemoryConfig.part_parents`) with the most of the part's voxels within
``part_gap_m`` of its own (geometric adjacency). A door or drawer goes first to a storage piece
whose footprint holds it: the fronts of two chests side by side stand a few centimetres apart, so
a drawer's edge is adjacent to the neighbour's carcass while its own carcass may show only its top,
too far above a low drawer to be adjacent at all. The links are kept on both sides
(``Instance.parent`` and the parent's ``children``) and never form a cycle.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from scipy.spatial import cKDTree

from agent.perception.instances import Instance


def attach_parts(instances: Mapping[int, Instance], live_instances: Sequence[Instance], seen: set[int],
                 parents: Mapping[str, tuple[str, ...]], gap_m: float) -> None:
    """(Re)decide the parent of every part seen this frame and of every part without a live parent.

    A part keeps its parent when no candidate is adjacent any more (an opened drawer pulled clear).

    Args:
        instances: every instance of the memory by id, gone ones included.
        live_instances: the instances not gone, by id.
        seen: ids created or updated by this frame.
        parents: part category -> the categories its parent may have.
        gap_m: how close a part's voxel must come to a candidate's to count as adjacent.
    """
    live = {inst.id: inst for inst in live_instances}
    trees: dict[int, cKDTree] = {}
    for inst in live.values():
        allowed = parents.get(inst.label)
        if allowed is None:
            continue
        has_parent = inst.parent is not None and inst.parent in live
        if has_parent and inst.id not in seen:
            continue
        best, best_rank = None, (False, 0, -np.inf)
        points = inst.points()
        centre = inst.centroid[:2]
        for candidate in live.values():
            if candidate.label not in allowed or is_ancestor(instances, inst.id, candidate.id):
                continue  # (an instance is its own ancestor, so it is never its own parent)
            if candidate.id not in trees:
                trees[candidate.id] = cKDTree(candidate.points())
            distance, _ = trees[candidate.id].query(points, distance_upper_bound=gap_m)
            holds = inst.label != "handle" and _footprint_holds(candidate, centre, gap_m)
            nearness = -float(np.linalg.norm(candidate.centroid[:2] - centre))  # among holders none touches
            rank = (holds, int(np.isfinite(distance).sum()), nearness)
            if (holds or rank[1] > 0) and rank > best_rank:
                best, best_rank = candidate.id, rank
        if best is not None and best != inst.parent:
            set_parent(instances, inst, best)


def set_parent(instances: Mapping[int, Instance], inst: Instance, parent_id: int) -> None:
    """Link ``inst`` under ``parent_id``, taking it off its old parent's children.

    Args:
        instances: every instance of the memory by id.
        inst: the part.
        parent_id: the id of its new parent, which must be in ``instances``.
    """
    if inst.parent is not None and inst.parent in instances:
        old = instances[inst.parent]
        if inst.id in old.children:
            old.children.remove(inst.id)
    inst.parent = parent_id
    parent = instances[parent_id]
    if inst.id not in parent.children:
        parent.children.append(inst.id)


def is_ancestor(instances: Mapping[int, Instance], ancestor: int, of: int) -> bool:
    """Whether ``ancestor`` is ``of`` or above it, so attaching it under ``of`` would make a cycle.

    Args:
        instances: every instance of the memory by id.
        ancestor: the id that might lie above.
        of: the id whose parents are followed.

    Returns:
        True when ``ancestor`` is ``of`` or above it.
    """
    seen = set()
    current: int | None = of
    while current is not None and current not in seen:
        if current == ancestor:
            return True
        seen.add(current)
        current = instances[current].parent if current in instances else None
    return False


def _footprint_holds(candidate: Instance, centre: np.ndarray, gap_m: float) -> bool:
    """Whether ``centre`` (x, y) lies over the candidate's footprint grown by ``gap_m`` (a front
    stands a little before its carcass)."""
    if not len(candidate.keys):
        return False
    lo, hi = candidate.bounds
    return bool(np.all(lo[:2] - gap_m <= centre) and np.all(centre <= hi[:2] + gap_m))
