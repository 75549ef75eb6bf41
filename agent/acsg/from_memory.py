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
- a drawer sweeps its front's box pulled out by ``drawer_pull_m``; a door sweeps its front and
  handle turned about its hinge from closed to ``door_swing_rad``, boxed a few centimetres at a
  time: past the quarter turn, the door swings on back over its hinge's side, as household hinges
  let it (`DOOR_SWING_RAD`).
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
from agent.perception.part_motion import rotation_about

PARTS = ("door", "drawer")
HANDLE = "handle"
#: Twice how far a thing's seen bottom may sink into what it stands on: a voxel and its noise. A mug
#: at a table's back corner, its lowest voxel 2 cm under the table's highest, stood on nothing in the
#: graph at 3 cm (occlusion 1069 of tuning-wide).
SUPPORT_GAP_M = 0.05
INSIDE_MARGIN_M = 0.01
#: How far (rad) a door may swing open: furniture hinges let a door on past square, about 100°, its
#: leaf and handle then back over the hinge's side. A thing standing there, beside the hinge, is
#: in the door's way though the robot's own opening (75°) would pass it (occlusion 1054, 1064 and
#: 1116 of tuning-wide: a can or a jar 3-4 cm beside a hinge).
DOOR_SWING_RAD = 1.75  # as the simulated furniture's doors (`worlds.storage_layout`)
#: Steps of the swing, and the greatest size of the cells of a door's front (m), at which it is
#: boxed (`door_sweep`): 2.8° steps move a cell at most 2.4 cm at a door's 0.5 m edge.
SWING_STEPS, SWEEP_CELL_M = 36, 0.04


def memory_detections(memory: InstanceMemory, toward: Sequence[float], drawer_pull_m: float = 0.25,
                      vacated: Mapping[int, tuple[np.ndarray, np.ndarray]] | None = None,
                      door_swing_rad: float = DOOR_SWING_RAD) -> list[Detection]:
    """One detection per live remembered instance, with its relation, the box around its voxels
    (``box`` hint) and, for parts, their swept box.

    ``toward`` is where the robot looks from (the camera position), which orients front normals.
    ``vacated``: instance id -> the (lo, hi) box it filled before it was moved away.

    Args:
        memory: the remembered instances.
        toward: where the robot looks from.
        drawer_pull_m: how far a drawer's swept box reaches out.
        vacated: the boxes of things moved away.
        door_swing_rad: how far a door's swept box follows it open.

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
        lo, hi = inst.bounds
        hints: dict[str, Any] = {"box": (lo.round(4).tolist(), hi.round(4).tolist())}
        if inst.id in absorbed:
            hints["absorbed"] = tuple(absorbed[inst.id])
        if inst.label in PARTS:
            swept = _swept_boxes(memory, inst, by_id, np.asarray(toward, dtype=float), drawer_pull_m,
                                 door_swing_rad)
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


def _swept_boxes(memory: InstanceMemory, part: Instance, by_id: dict[int, Instance], toward: np.ndarray,
                 drawer_pull_m: float, door_swing_rad: float) -> tuple[list, list] | None:
    """(lo, hi) corners of the boxes whose union holds what the part passes through when it opens,
    or None without a handle or where its geometry cannot be told: for a drawer, its front's box
    and that box pulled out (one box, corners (3,)); for a door, its front's and its handle's cells
    along the swing (`door_sweep`, corners (N, 3))."""
    handles = [by_id[c] for c in part.children if c in by_id and by_id[c].label == HANDLE]
    if not handles:
        return None
    try:
        geometry = handle_geometry(memory, handles[0].id, toward, kind=part.label)
    except GeometryError:
        return None
    lo, hi = part.bounds
    if geometry.kind == "drawer":
        pulled = drawer_pull_m * geometry.normal
        corners = np.vstack([lo, hi, lo + pulled, hi + pulled])
        return corners.min(axis=0).round(4).tolist(), corners.max(axis=0).round(4).tolist()
    assert geometry.hinge_point is not None and geometry.hinge_axis is not None
    boxes = [door_sweep(box, geometry.hinge_point, geometry.hinge_axis, door_swing_rad)
             for box in ((lo, hi), handles[0].bounds)]
    return (np.concatenate([b[0] for b in boxes]).round(4).tolist(),
            np.concatenate([b[1] for b in boxes]).round(4).tolist())


def door_sweep(box: Box, hinge_point: np.ndarray, hinge_axis: np.ndarray, upto_rad: float,
               cell_m: float = SWEEP_CELL_M, steps: int = SWING_STEPS) -> Box:
    """Boxes whose union holds what ``box`` passes through turning about the hinge line
    (``hinge_point``, unit ``hinge_axis``, opening positive) from 0 to ``upto_rad``.

    The box is cut into cells at most ``cell_m`` across (not along the hinge, where turning does
    not move it), and each cell is boxed between consecutive angles: a box around the whole door
    at 45° would be a square as deep as the door is wide, where the door is a thin slab.

    Args:
        box: (lo, hi) corners of what turns: a door's front, its handle.
        hinge_point: a point of the hinge line.
        hinge_axis: the line's unit direction.
        upto_rad: the widest opening.
        cell_m: the cells' greatest size.
        steps: how many steps the opening is cut into.

    Returns:
        (lo, hi) corners, each (N, 3).
    """
    lo, hi = (np.asarray(v, dtype=float) for v in box)
    k = np.asarray(hinge_axis, dtype=float)
    cuts = [np.linspace(lo[i], hi[i], 2 if abs(k[i]) > 0.9 else max(2, int(np.ceil((hi[i] - lo[i]) / cell_m)) + 1))
            for i in range(3)]
    cells = [np.array([[a, b] for a, b in zip(c[:-1], c[1:])]) for c in cuts]
    corners = np.array([[x, y, z] for xs in cells[0] for ys in cells[1] for zs in cells[2]
                        for x in xs for y in ys for z in zs]).reshape(-1, 8, 3)
    arms = corners - hinge_point
    turned = np.stack([arms @ rotation_about(k, a).T for a in np.linspace(0.0, upto_rad, steps + 1)]) \
        + hinge_point  # (angles, cells, 8, 3)
    pairs = np.concatenate([turned[:-1], turned[1:]], axis=2)  # each cell between consecutive angles
    return pairs.min(axis=2).reshape(-1, 3), pairs.max(axis=2).reshape(-1, 3)
