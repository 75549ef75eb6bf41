"""Detections for the explorer from the perception memory: labels, spatial relations, and the space
each door or drawer sweeps.

The explorer (Algorithm 1) needs, per object, the parent it belongs to, stands on or lies inside
(Algorithm 2's object-object edges), and for the verifier the box a part sweeps when it opens, so an
object standing in that box is found to block it. All of it is read from the remembered geometry:

- a handle belongs to its door or drawer, and a door or drawer to its storage piece (the memory
  attaches parts by adjacency);
- any other thing lies *inside* the smallest box that contains its centre: a storage piece's, an
  open drawer's, a box put over it, or the box a thing moved away filled before it was moved
  (``vacated``: a cup found where a box was lifted from lay inside the box), that box reaching
  down to the thing's bottom (a box seen from above, standing in a larger one, is remembered by its
  top few centimetres, and what it covered stood below them);
- else it stands *on* the highest thing whose top is below its bottom (within ``SUPPORT_GAP_M`` / 2
  above it) and under its centre (a piece's top counting its parts: a chest whose front is all
  drawers), however far below: a thing seen only from above, its bottom unseen, does not float;
- a drawer sweeps its front's box pulled out by ``drawer_pull_m``; a door sweeps the square in
  front of it whose side is the door's width (the quarter circle it swings through, boxed).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from agent.acsg.interfaces import Detection
from agent.perception.directions import GeometryError
from agent.perception.instances import Instance, family_bounds
from agent.perception.memory import InstanceMemory
from agent.perception.part_geometry import handle_geometry

PARTS = ("door", "drawer")
HANDLE = "handle"
#: Twice how far a thing's seen bottom may sink into what it stands on: a voxel and its noise. A mug
#: at a table's back corner, its lowest voxel 2 cm under the table's highest, stood on nothing in the
#: graph at 3 cm (occlusion 1069 of tuning-wide).
SUPPORT_GAP_M = 0.05
INSIDE_MARGIN_M = 0.01


def memory_detections(memory: InstanceMemory, toward: Sequence[float], drawer_pull_m: float = 0.25,
                      vacated: Mapping[int, tuple[np.ndarray, np.ndarray]] | None = None) -> list[Detection]:
    """One detection per live remembered instance, with its relation and, for parts, their swept box.

    ``toward`` is where the robot looks from (the camera position), which orients front normals.
    ``vacated``: instance id -> the (lo, hi) box it filled before it was moved away.

    Args:
        memory: the remembered instances.
        toward: where the robot looks from.
        drawer_pull_m: how far a drawer's swept box reaches out.
        vacated: the boxes of things moved away.

    Returns:
        The detections.
    """
    live = memory.live()
    by_id = {inst.id: inst for inst in live}
    boxes = {inst.id: family_bounds(inst, by_id) for inst in live}
    absorbed: dict[int, list[str]] = {}
    for alias in memory.aliases:
        absorbed.setdefault(memory.get(alias).id, []).append(str(alias))
    detections = []
    for inst in live:
        parent, relation = _relation(inst, live, by_id, boxes, vacated or {})
        hints: dict[str, Any] = {"absorbed": tuple(absorbed[inst.id])} if inst.id in absorbed else {}
        if inst.label in PARTS:
            swept = _swept_box(memory, inst, by_id, np.asarray(toward, dtype=float), drawer_pull_m)
            if swept is not None:
                hints["swept"] = swept
        detections.append(Detection(str(inst.id), inst.label, None if parent is None else str(parent), relation,
                                    {"colour": inst.colour} if inst.colour else {}, inst.centroid, inst.extent,
                                    hints))
    return detections


Box = tuple[np.ndarray, np.ndarray]


def _relation(inst: Instance, live: list[Instance], by_id: dict[int, Instance], boxes: Mapping[int, Box],
              vacated: Mapping[int, Box]) -> tuple[int | None, str | None]:
    if inst.label in (*PARTS, HANDLE):
        return (inst.parent, "belongs") if inst.parent in by_id else (None, None)
    centre = inst.centroid
    lo, _ = boxes[inst.id]
    own = _volume(inst.bounds)
    containers = [(_reaching_down(box, lo[2]), other_id)  # the lower part of a thing moved away was hidden
                  for other_id, box in vacated.items() if other_id != inst.id]
    containers += [(other.bounds, other.id) for other in live  # own boxes: an open door's swing contains nothing
                   if other.id != inst.id and other.label not in ("door", HANDLE)]
    inside = [(_volume(box), other_id) for box, other_id in containers if _contains(box, centre) and _volume(box) > own]
    if inside:
        return min(inside)[1], "inside"
    supports = []
    for other in live:
        if other.id == inst.id or other.label in (HANDLE,):
            continue
        other_lo, other_hi = boxes[other.id]
        below = lo[2] - other_hi[2] + SUPPORT_GAP_M / 2 >= 0.0
        under = np.all(other_lo[:2] <= centre[:2]) and np.all(centre[:2] <= other_hi[:2])
        if below and under:
            supports.append(other)
    if supports:  # the highest: a thing seen only from above (its bottom unseen) still stands on it
        top = max(supports, key=lambda other: boxes[other.id][1][2])
        return (top.parent, "on") if top.label in PARTS and top.parent in by_id else (top.id, "on")
    return None, None


def _reaching_down(box: Box, bottom: float) -> Box:
    """``box`` with its bottom at ``bottom`` where that is lower."""
    lo, hi = (np.asarray(corner, dtype=float) for corner in box)
    return np.array([lo[0], lo[1], min(float(lo[2]), bottom)]), hi


def _contains(box: Box, point: np.ndarray) -> bool:
    lo, hi = box
    return bool(np.all(lo + INSIDE_MARGIN_M <= point) and np.all(point <= hi - INSIDE_MARGIN_M))


def _volume(box: Box) -> float:
    lo, hi = box
    return float(np.prod(np.maximum(hi - lo, 1e-3)))


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



