"""Detections for the explorer from the perception memory: labels, spatial relations, and the space
each door or drawer sweeps.

The explorer (Algorithm 1) needs, per object, the parent it belongs to, stands on or lies inside
(Algorithm 2's object-object edges), and for the verifier the box a part sweeps when it opens, so an
object standing in that box is found to block it. All of it is read from the remembered geometry:

- a handle belongs to its door or drawer, and a door or drawer to its storage piece (the memory
  attaches parts by adjacency);
- any other thing lies *inside* the smallest remembered box that contains its centre (a storage
  piece, or a box put over it), else stands *on* the highest thing whose top is just below its
  bottom and under its centre;
- a drawer sweeps its front's box pulled out by ``drawer_pull_m``; a door sweeps the square in
  front of it whose side is the door's width (the quarter circle it swings through, boxed).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from agent.acsg.interfaces import Detection
from agent.perception.geometry import GeometryError, handle_geometry
from agent.perception.memory import Instance, InstanceMemory

PARTS = ("door", "drawer")
HANDLE = "handle"
SUPPORT_GAP_M = 0.03  # a thing stands on a surface whose top is at most this far below its bottom
INSIDE_MARGIN_M = 0.01


def memory_detections(memory: InstanceMemory, toward: Sequence[float], drawer_pull_m: float = 0.25) -> list[Detection]:
    """One detection per live remembered instance, with its relation and, for parts, their swept box.

    ``toward`` is where the robot looks from (the camera position), which orients front normals.
    """
    live = memory.live()
    by_id = {inst.id: inst for inst in live}
    detections = []
    for inst in live:
        parent, relation = _relation(inst, live, by_id)
        hints = {}
        if inst.label in PARTS:
            swept = _swept_box(memory, inst, by_id, np.asarray(toward, dtype=float), drawer_pull_m)
            if swept is not None:
                hints["swept"] = swept
        detections.append(Detection(str(inst.id), inst.label, None if parent is None else str(parent), relation,
                                    {"colour": inst.colour} if inst.colour else {}, inst.centroid, inst.extent,
                                    hints))
    return detections


def _relation(inst: Instance, live: list[Instance], by_id: dict[int, Instance]) -> tuple[int | None, str | None]:
    if inst.label in (*PARTS, HANDLE):
        return (inst.parent, "belongs") if inst.parent in by_id else (None, None)
    centre = inst.centroid
    lo, _ = inst.bounds
    containers = [other for other in live if other.id != inst.id and other.label not in (*PARTS, HANDLE)
                  and _contains(other, centre) and _volume(other) > _volume(inst)]
    if containers:
        return min(containers, key=_volume).id, "inside"
    supports = []
    for other in live:
        if other.id == inst.id or other.label in (HANDLE,):
            continue
        other_lo, other_hi = other.bounds
        below = 0.0 <= lo[2] - other_hi[2] + SUPPORT_GAP_M / 2 <= SUPPORT_GAP_M * 1.5
        under = np.all(other_lo[:2] <= centre[:2]) and np.all(centre[:2] <= other_hi[:2])
        if below and under:
            supports.append(other)
    if supports:
        top = max(supports, key=lambda other: other.bounds[1][2])
        return (top.parent, "on") if top.label in PARTS and top.parent in by_id else (top.id, "on")
    return None, None


def _contains(box: Instance, point: np.ndarray) -> bool:
    lo, hi = box.bounds
    return bool(np.all(lo + INSIDE_MARGIN_M <= point) and np.all(point <= hi - INSIDE_MARGIN_M))


def _volume(inst: Instance) -> float:
    return float(np.prod(np.maximum(inst.extent, 1e-3)))


def _swept_box(memory: InstanceMemory, part: Instance, by_id: dict[int, Instance], toward: np.ndarray,
               drawer_pull_m: float) -> tuple[list[float], list[float]] | None:
    """(lo, hi) corners of the box the part passes through when it opens, or None without a handle."""
    handles = [by_id[c] for c in part.children if c in by_id and by_id[c].label == HANDLE]
    if not handles:
        return None
    try:
        geometry = handle_geometry(memory, handles[0].id, toward, kind=part.label)
    except GeometryError:
        return None
    lo, hi = part.bounds
    normal = geometry.normal
    if geometry.kind == "drawer":
        corners = np.vstack([lo, hi, lo + drawer_pull_m * normal, hi + drawer_pull_m * normal])
    else:
        width = float(np.linalg.norm((hi - lo)[:2]))
        corners = np.vstack([lo, hi, lo + width * normal, hi + width * normal])
    return corners.min(axis=0).round(4).tolist(), corners.max(axis=0).round(4).tolist()



