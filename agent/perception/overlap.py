"""Whether a detection is a remembered instance seen again: the memory's merge test.

Merging follows RoboEXP (after ConceptGraphs): the labels must agree, and the geometry must
overlap. Overlap is measured three ways, any one of which may pass:

- 3D IoU of the voxel sets, counted with a one-voxel tolerance (two views of one surface rarely
  quantise to the very same voxels);
- containment: the share of the *smaller* set lying on the larger. A second view of an object
  often sees a different side, so its voxels are a small, fully overlapping subset of what is
  remembered and their IoU is low although they are plainly the same thing;
- the IoU of the axis-aligned boxes, the centroid/extent test: it catches a re-observation whose
  surface samples fall between the remembered ones (a far, sparse view after a near, dense one).
  Its threshold is high (0.7) because a box nested in a same-label box (the recursive task's
  shells) has a box IoU of 0.4-0.7 with it while sharing no surface.

A fourth catches a piece of furniture seen in fragments: the corner of a cabinet's plinth seen by
the wrist camera below the door, after the head camera saw only its top, shares no surface with the
top and lies outside its box, so it became a second cabinet, which the explorer then tried to open
(a cabinet with no door of its own; the memory merged the two a view later, but the graph had the
second already). A detection whose box lies wholly within the box of a same-label instance with its
parts (`NESTED_SHARE`; the cabinet with its door) and fills at most half of it (`NESTED_VOLUME`) is
a part of that instance seen from a new side; the box is grown by a voxel for it, as the overlap
is counted with a voxel's tolerance: the wrist camera saw only the lower edge of a book's far side,
whose voxels reached one beyond the box of the book seen from the front. A thing nested in a same-label thing (a shell over a smaller
box) is never seen while the outer stands over it: once the outer is lifted away it no longer
surrounds it.

Two same-label things side by side (the two doors of a cabinet) touch only along an edge, so all
three stay low and they remain two instances: the seam between two doors puts about 5 % of
either's voxels within a voxel of the other, while two head-camera views of one cabinet from bases
0.6 m apart share about 35 %; the containment threshold (0.3) sits between.
"""

from __future__ import annotations

import numpy as np

from agent.perception.frames import Detection
from agent.perception.instances import Instance, MemoryConfig
from agent.perception.voxels import centres, near_count

#: A detection whose box lies this share or more within a same-label instance's box, and fills at
#: most `NESTED_VOLUME` of it, is part of that instance (see the module docstring).
NESTED_SHARE, NESTED_VOLUME = 0.95, 0.5


def overlap(detection: Detection, inst: Instance, config: MemoryConfig,
            family: tuple[np.ndarray, np.ndarray] | None = None) -> float:
    """How well a detection overlaps a remembered instance of its label, for ranking matches.

    Args:
        detection: a detection of the newest frame.
        inst: a live instance with voxels.
        config: the merge thresholds (``merge_iou``, ``merge_containment``, ``merge_box_iou``).
        family: the box around the instance and its parts (a cabinet with its door), which the
            nested test uses; the instance's own box when None.

    Returns:
        The best of the three overlap measures that passes its threshold, else 0.
    """
    small, large = sorted((detection.keys, inst.keys), key=len)
    near = near_count(small, large)
    containment = near / len(small)
    iou = near / (len(detection.keys) + len(inst.keys) - near)
    seen = box_of(detection.keys, config.voxel_m)
    box = _box_iou(seen, inst.bounds)
    passing = [value for value, threshold in ((iou, config.merge_iou), (containment, config.merge_containment),
                                              (box, config.merge_box_iou)) if value >= threshold]
    lo, hi = inst.bounds if family is None else family
    around = (lo - config.voxel_m, hi + config.voxel_m)  # a face seen edge-on quantises a voxel beyond
    if _volume(seen) <= NESTED_VOLUME * _volume(around) and share_within(seen, around) >= NESTED_SHARE:
        passing.append(NESTED_SHARE)
    return max(passing, default=0.0)


def box_of(keys: np.ndarray, voxel_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The box around voxels, to their outer faces.

    Args:
        keys: packed voxel keys (`agent.perception.voxels`), at least one.
        voxel_m: the voxels' size (m).

    Returns:
        (lo, hi) corners.
    """
    pts = centres(keys, voxel_m)
    return pts.min(axis=0) - voxel_m / 2, pts.max(axis=0) + voxel_m / 2


def _volume(box: tuple[np.ndarray, np.ndarray]) -> float:
    return float(np.prod(np.clip(box[1] - box[0], 0.0, None)))


def share_within(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> float:
    """The share of box ``a``'s volume inside box ``b`` (of its area, for boxes in the plane).

    Args:
        a: (lo, hi) corners of one box, of any dimension.
        b: (lo, hi) corners of the other, of the same dimension.

    Returns:
        The share, 0 where ``a`` is empty.
    """
    inter = np.prod(np.clip(np.minimum(a[1], b[1]) - np.maximum(a[0], b[0]), 0.0, None))
    return float(inter / _volume(a)) if _volume(a) > 0 else 0.0


def _box_iou(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> float:
    """IoU of two axis-aligned boxes given as (lo, hi)."""
    inter = np.prod(np.clip(np.minimum(a[1], b[1]) - np.maximum(a[0], b[0]), 0.0, None))
    union_volume = np.prod(a[1] - a[0]) + np.prod(b[1] - b[0]) - inter
    return float(inter / union_volume) if union_volume > 0 else 0.0
