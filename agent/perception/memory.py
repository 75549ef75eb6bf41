"""Instance memory across views: RoboEXP's low-level memory (§IV, Memory Module) as voxel sets.

Each frame is cut into detections (`agent.perception.frames`), and each detection either merges
with a remembered instance or becomes a new one. Merging follows the paper (after ConceptGraphs):
the labels must agree, and the geometry must overlap. Overlap is measured three ways, any one of
which may pass:

- 3D IoU of the voxel sets, counted with a one-voxel tolerance (two views of one surface rarely
  quantise to the very same voxels);
- containment: the share of the *smaller* set lying on the larger. A second view of an object
  often sees a different side, so its voxels are a small, fully overlapping subset of what is
  remembered and their IoU is low although they are plainly the same thing;
- the IoU of the axis-aligned boxes, the centroid/extent test: it catches a re-observation whose
  surface samples fall between the remembered ones (a far, sparse view after a near, dense one).
  Its threshold is high (0.7) because a box nested in a same-label box (the recursive task's
  shells) has a box IoU of 0.4-0.7 with it while sharing no surface.

Two same-label things side by side (the two doors of a cabinet) touch only along an edge, so all
three stay low and they remain two instances: the seam between two doors puts about 5 % of
either's voxels within a voxel of the other, while two head-camera views of one cabinet from bases
0.6 m apart share about 35 %; the containment threshold (0.3) sits between. The simulator's
segmentation ids are never used to match: they are per-frame segments, kept only as ``hint``.

Stale voxels go by a depth test against the newest frame, before it is merged: a remembered voxel
that projects into the image *in front of* what the camera now sees there, by more than a margin,
should have been seen and was not, so it is no longer there (a door swung open, an object picked
away). Voxels behind the observed surface (occluded) or outside the image are kept. The observed
depth is taken as the nearest return in the pixel's 3x3 neighbourhood, so a voxel on the rim of an
object that still stands there is not eaten away by the background just beside its silhouette.
The depth test cannot clear what lies within the margin of the surface behind it (a cup's base
on the table), so once most of an instance's visible voxels fail it, the thing is taken to have
moved and its visible rest goes too, unless its own pixel still shows its label at its depth.
An instance left with no voxels is marked gone. A thing that moved reappears as a new instance
wherever it no longer overlaps its old voxels (a cup picked away); the memory does not guess that
it is the same thing, and a caller that knows (the skill that moved it) says so with
`InstanceMemory.merge`. A door swung open usually keeps its identity by itself: the strip along its
hinge is hidden behind the open door, not stale, and the open door overlaps it.

Parts (handles, doors, drawers) are attached to a parent: a handle to the door or drawer it stands
on, a door or drawer to the storage piece it belongs to. The labels say only what kind of thing a
part is, not whose it is, so the parent is the instance of an allowed category with the most of
the part's voxels within ``part_gap_m`` of its own (geometric adjacency).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.ndimage import minimum_filter
from scipy.spatial import cKDTree

from agent.mapping.camera import Intrinsics
from agent.perception.frames import Detection, FrameLabel, check_frame, check_labels, detect, frame_labels
from agent.perception.voxels import centres, near_count, pack, union, voxel_indices

#: Categories of storage furniture, as the world labels them (worlds.vocabulary.STORAGE_CATEGORIES;
#: the agent does not import the world, so the words are repeated here).
STORAGE_CATEGORIES = ("cabinet", "drawer chest", "wardrobe", "nightstand", "fridge", "dishwasher", "counter")
#: Part category -> the categories its parent may have. Flaps are labelled "door" by the world.
PART_PARENTS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("handle", ("door", "drawer")),
    ("door", STORAGE_CATEGORIES),
    ("drawer", STORAGE_CATEGORIES),
)


@dataclass(frozen=True)
class MemoryConfig:
    """Thresholds of the instance memory; lengths in metres.

    ``voxel_m`` 1 cm resolves a 1.6 cm handle bar at arm's length. ``stale_margin_m`` must exceed
    depth noise plus half a voxel diagonal, or surfaces still there would be forgotten.
    ``stale_majority``: the share of an instance's visible voxels that must fail the depth test
    before its unconfirmed rest is cleared too (see `InstanceMemory._forget_stale`).
    ``part_gap_m`` 5 cm: a handle's bar stands 3.5 cm proud of its front on posts the camera
    rarely sees, so from straight ahead only the bar's face, 4.3 cm out, is in memory.
    ``no_return_is_free``: whether a pixel without a depth return (0) counts as seeing through to
    infinity (true in simulation, where 0 means "beyond the far plane") or as seeing nothing.
    """

    voxel_m: float = 0.01
    min_pixels: int = 10
    max_depth_m: float | None = 4.0
    merge_iou: float = 0.2
    merge_containment: float = 0.3
    merge_box_iou: float = 0.7
    stale_margin_m: float = 0.03
    stale_majority: float = 0.5
    no_return_is_free: bool = False
    part_gap_m: float = 0.05
    part_parents: tuple[tuple[str, tuple[str, ...]], ...] = PART_PARENTS

    def __post_init__(self) -> None:
        for name in ("voxel_m", "stale_margin_m", "part_gap_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"memory.{name}: {getattr(self, name)} must be positive")
        for name in ("merge_iou", "merge_containment", "merge_box_iou", "stale_majority"):
            if not 0 < getattr(self, name) <= 1:
                raise ValueError(f"memory.{name}: {getattr(self, name)} must lie in (0, 1]")


@dataclass(eq=False)  # identity is the id; arrays inside would make == ambiguous
class Instance:
    """One remembered thing. ``id`` is the memory's own, stable for the instance's life.

    ``keys``/``hits``: its voxels (sorted packed keys, `agent.perception.voxels`) and how many pixels
    have fallen in each over all frames. ``hint``: the segmentation id it had when last seen (a
    per-frame id, not an identity). Frames are numbered by `InstanceMemory.integrate` from 0.
    """

    id: int
    label: str
    colour: str | None
    keys: np.ndarray
    hits: np.ndarray
    voxel_m: float
    first_seen: int
    last_seen: int
    hint: int | None = None
    frames: set[int] = field(default_factory=set)  # the frames it was detected in
    parent: int | None = None
    children: list[int] = field(default_factory=list)
    gone: bool = False
    gone_frame: int | None = None

    @property
    def voxel_count(self) -> int:
        return int(len(self.keys))

    def points(self, min_hits: int = 1) -> np.ndarray:
        """Voxel centres (N, 3), world frame; ``min_hits`` > 1 keeps only voxels seen that often."""
        keys = self.keys if min_hits <= 1 else self.keys[self.hits >= min_hits]
        return centres(keys, self.voxel_m)

    @property
    def centroid(self) -> np.ndarray:
        """Mean of the voxel centres (world frame); NaN when no voxels are left."""
        return self.points().mean(axis=0) if len(self.keys) else np.full(3, np.nan)

    @property
    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) corners of the axis-aligned box around the voxels (their outer faces)."""
        if not len(self.keys):
            return np.full(3, np.nan), np.full(3, np.nan)
        pts = self.points()
        half = self.voxel_m / 2
        return pts.min(axis=0) - half, pts.max(axis=0) + half

    @property
    def extent(self) -> np.ndarray:
        """Size (dx, dy, dz) of `bounds`."""
        lo, hi = self.bounds
        return hi - lo


@dataclass(frozen=True)
class FrameUpdate:
    """What one `InstanceMemory.integrate` changed: the memory's diff, as the ACSG needs it.

    ``created``/``updated``: instances new in this frame / seen again. ``shrunk``: id -> voxels
    removed by the depth test. ``gone``: instances left with no voxels. ``absorbed``: old id -> the
    id it was merged into (one detection bridged two remembered pieces of the same thing).
    """

    frame: int
    created: tuple[int, ...]
    updated: tuple[int, ...]
    shrunk: dict[int, int]
    gone: tuple[int, ...]
    absorbed: dict[int, int]


class InstanceMemory:
    """Instances fused over frames; see the module docstring for the rules."""

    def __init__(self, config: MemoryConfig = MemoryConfig()) -> None:
        self.config = config
        self.instances: dict[int, Instance] = {}
        #: Ids absorbed into another instance -> the id they live on as.
        self.aliases: dict[int, int] = {}
        self.frame = -1
        self._next_id = 0
        self._parents = dict(config.part_parents)

    # --- reading -----------------------------------------------------------------------------

    def live(self) -> list[Instance]:
        """Instances not gone, by id."""
        return [inst for _, inst in sorted(self.instances.items()) if not inst.gone]

    def get(self, instance_id: int) -> Instance:
        """The instance ``instance_id`` (following aliases of absorbed ids)."""
        while instance_id in self.aliases:
            instance_id = self.aliases[instance_id]
        try:
            return self.instances[instance_id]
        except KeyError:
            raise KeyError(f"instance_id: {instance_id} is not in the memory") from None

    def with_label(self, label: str) -> list[Instance]:
        return [inst for inst in self.live() if inst.label == label]

    # --- writing -----------------------------------------------------------------------------

    def integrate(self, observation: Any) -> FrameUpdate:
        """Fold in one `agent.observation.Observation` (or anything with the same fields)."""
        return self.integrate_frame(observation.depth, observation.segmentation, observation.labels,
                                    observation.intrinsics, observation.camera_to_world)

    def integrate_frame(
        self,
        depth: np.ndarray,
        segmentation: np.ndarray,
        labels: Mapping[int, Any] | Iterable[Any],
        intrinsics: Intrinsics,
        camera_to_world: np.ndarray,
    ) -> FrameUpdate:
        """Forget what the frame shows is no longer there, then merge what it shows into the memory.

        ``depth`` (H, W) linear metres with 0 = no return; ``segmentation`` (H, W) per-frame instance
        ids, -1 = nothing; ``labels`` per id (see `frames.frame_labels`); ``camera_to_world`` 4x4
        with OpenCV camera axes (x right, y down, z ahead).
        """
        cfg = self.config
        check_frame(depth, segmentation, intrinsics, camera_to_world)
        parsed = frame_labels(labels)
        check_labels(segmentation, parsed)  # a bad frame is refused before it changes anything
        self.frame += 1
        shrunk, gone = self._forget_stale(np.asarray(depth, dtype=float), np.asarray(segmentation), parsed, intrinsics,
                                          np.asarray(camera_to_world, dtype=float))
        detections = detect(depth, segmentation, parsed, intrinsics, camera_to_world,
                            cfg.voxel_m, cfg.min_pixels, cfg.max_depth_m)
        created, updated, absorbed = [], [], {}
        for detection in detections:
            matches = self._matches(detection)
            if not matches:
                created.append(self._create(detection).id)
                continue
            target = self.instances[matches[0]]
            for other in matches[1:]:
                if self.instances[other].frames & (target.frames | {self.frame}):
                    continue  # seen apart in one frame: two things, however close (stacked drawers)
                absorbed[other] = target.id
                self._absorb_instance(target, self.instances[other])
            self._absorb_detection(target, detection)
            updated.append(target.id)
        seen = set(created) | set(updated)
        self._attach_parts(seen)
        return FrameUpdate(self.frame, tuple(created), tuple(i for i in updated if i not in created),
                           shrunk, tuple(gone), absorbed)

    def merge(self, keep: int, other: int) -> Instance:
        """Declare ``other`` the same thing as ``keep``: voxels and children move over, ``other``
        becomes an alias of ``keep``. For callers who know what perception cannot (the door just
        opened is the door that was closed). Either may be gone; the result is live if it has voxels.
        """
        target, absorbed = self.get(keep), self.get(other)
        if target.id == absorbed.id:
            return target
        if target.label != absorbed.label:
            raise ValueError(f"other: instance {absorbed.id} is a {absorbed.label}, not a {target.label}")
        was_gone = target.gone
        self._absorb_instance(target, absorbed)
        target.last_seen = max(target.last_seen, absorbed.last_seen)
        if was_gone and len(target.keys):
            target.gone, target.gone_frame = False, None
            if target.parent is not None and target.parent in self.instances:
                self._set_parent(target, target.parent)
        return target

    def move(self, instance_id: int, motion: np.ndarray) -> list[int]:
        """Carry an instance and its parts (children, recursively) by the rigid ``motion`` (4x4,
        world frame, applied on the left); returns the ids moved.

        For the caller that moved the thing and knows how (a skill that pulled a drawer out by
        0.2 m, put a cup down elsewhere): the next view then finds it where it now is and merges
        with it, instead of reporting a new thing there and the old one gone. Voxel centres are
        moved and quantised again; voxels landing in one keep the sum of their hits.
        """
        motion = np.asarray(motion, dtype=float)
        if motion.shape != (4, 4) or not np.all(np.isfinite(motion)):
            raise ValueError(f"motion: a finite 4x4 transform is needed, got shape {motion.shape}")
        moved, todo = [], [self.get(instance_id).id]
        while todo:
            inst = self.instances[todo.pop()]
            if inst.id in moved:
                continue
            if len(inst.keys):
                points = inst.points() @ motion[:3, :3].T + motion[:3, 3]
                keys, inverse = np.unique(pack(voxel_indices(points, inst.voxel_m)), return_inverse=True)
                inst.keys = keys
                inst.hits = np.bincount(inverse, weights=inst.hits, minlength=len(keys)).astype(np.int32)
            moved.append(inst.id)
            todo.extend(c for c in inst.children if c in self.instances)
        return moved

    # --- stale voxels ------------------------------------------------------------------------

    def _forget_stale(self, depth: np.ndarray, segmentation: np.ndarray, labels: Mapping[int, FrameLabel],
                      intrinsics: Intrinsics, camera_to_world: np.ndarray) -> tuple[dict[int, int], list[int]]:
        """Delete voxels the frame looks through; returns (id -> voxels removed, ids now gone).

        Per instance, its voxels in the image are *visible* unless they lie behind the observed
        surface (occluded), and *stale* if they lie in front of it. When most of the visible
        voxels are stale (`MemoryConfig.stale_majority`), the thing has moved, and the visible
        rest goes too unless its own pixel shows the instance's label at its depth: the rest are
        the voxels within the margin of whatever the thing stood on or against (a cup's base on
        the table, a door's rim against the carcass), which the depth test alone cannot clear.
        The check is strict (the voxel's own pixel, no neighbourhood) because it runs only for
        instances already judged moved, where forgetting a rim voxel too many costs nothing.
        """
        cfg = self.config
        observed = np.where(depth > 0, depth, np.inf)
        nearest = minimum_filter(observed, size=3, mode="nearest")
        if not cfg.no_return_is_free:
            nearest = np.where(depth > 0, nearest, -np.inf)  # no return: no evidence either way
        label_of = np.full(segmentation.shape, "", dtype=object)
        for seg_id, label in labels.items():
            label_of[segmentation == seg_id] = label.category
        world_to_camera = np.linalg.inv(camera_to_world)
        shrunk: dict[int, int] = {}
        gone: list[int] = []
        for inst in self.live():
            cam = inst.points() @ world_to_camera[:3, :3].T + world_to_camera[:3, 3]
            z = cam[:, 2]
            ahead = z > 1e-6
            u = np.full(len(z), -1.0)
            v = np.full(len(z), -1.0)
            u[ahead] = intrinsics.fx * cam[ahead, 0] / z[ahead] + intrinsics.cx
            v[ahead] = intrinsics.fy * cam[ahead, 1] / z[ahead] + intrinsics.cy
            inside = ahead & (u >= 0) & (u < intrinsics.width) & (v >= 0) & (v < intrinsics.height)
            if not inside.any():
                continue
            cols, rows = u[inside].astype(int), v[inside].astype(int)
            surface = nearest[rows, cols]
            stale = np.zeros(len(z), dtype=bool)
            stale[inside] = z[inside] < surface - cfg.stale_margin_m
            visible = np.zeros(len(z), dtype=bool)
            visible[inside] = np.isfinite(surface) & (z[inside] <= surface + cfg.stale_margin_m)
            if visible.sum() and stale.sum() >= cfg.stale_majority * visible.sum():
                confirmed = np.zeros(len(z), dtype=bool)
                confirmed[inside] = (label_of[rows, cols] == inst.label) & (
                    np.abs(z[inside] - depth[rows, cols]) <= cfg.stale_margin_m)
                stale |= visible & ~confirmed
            if not stale.any():
                continue
            inst.keys, inst.hits = inst.keys[~stale], inst.hits[~stale]
            shrunk[inst.id] = int(stale.sum())
            if not len(inst.keys):
                self._forget(inst)
                gone.append(inst.id)
        return shrunk, gone

    def _forget(self, inst: Instance) -> None:
        """Mark ``inst`` gone and take it off its parent's children (its ``parent`` stays, as history)."""
        inst.gone, inst.gone_frame = True, self.frame
        if inst.parent is not None and inst.parent in self.instances:
            siblings = self.instances[inst.parent].children
            if inst.id in siblings:
                siblings.remove(inst.id)

    # --- merging -----------------------------------------------------------------------------

    def _matches(self, detection: Detection) -> list[int]:
        """Ids of live same-label instances the detection overlaps enough, best first."""
        scored = []
        for inst in self.live():
            if inst.label != detection.label or not len(inst.keys):
                continue
            score = self._overlap(detection, inst)
            if score > 0:
                scored.append((-score, inst.id))
        return [i for _, i in sorted(scored)]

    def _overlap(self, detection: Detection, inst: Instance) -> float:
        """The best of the three overlap measures that passes its threshold, else 0."""
        cfg = self.config
        small, large = sorted((detection.keys, inst.keys), key=len)
        near = near_count(small, large)
        containment = near / len(small)
        iou = near / (len(detection.keys) + len(inst.keys) - near)
        box = _box_iou(_bounds(detection.keys, cfg.voxel_m), inst.bounds)
        passing = [value for value, threshold in ((iou, cfg.merge_iou), (containment, cfg.merge_containment),
                                                  (box, cfg.merge_box_iou)) if value >= threshold]
        return max(passing, default=0.0)

    def _create(self, detection: Detection) -> Instance:
        inst = Instance(self._next_id, detection.label, detection.colour, detection.keys, detection.hits,
                        self.config.voxel_m, self.frame, self.frame, detection.hint, {self.frame})
        self.instances[inst.id] = inst
        self._next_id += 1
        return inst

    def _absorb_detection(self, inst: Instance, detection: Detection) -> None:
        inst.keys, inst.hits = union(inst.keys, inst.hits, detection.keys, detection.hits)
        inst.last_seen, inst.hint = self.frame, detection.hint
        inst.frames.add(self.frame)
        if detection.colour is not None:
            inst.colour = detection.colour

    def _absorb_instance(self, target: Instance, other: Instance) -> None:
        """Fold ``other`` into ``target``: voxels, children; ``other`` is removed and aliased."""
        target.keys, target.hits = union(target.keys, target.hits, other.keys, other.hits)
        target.first_seen = min(target.first_seen, other.first_seen)
        target.frames |= other.frames
        for child_id in other.children:
            self.instances[child_id].parent = target.id
            if child_id not in target.children:
                target.children.append(child_id)
        if other.parent is not None and other.parent in self.instances:
            siblings = self.instances[other.parent].children
            if other.id in siblings:
                siblings.remove(other.id)
        if target.parent is None and other.parent is not None:
            self._set_parent(target, other.parent)
        del self.instances[other.id]
        self.aliases[other.id] = target.id

    # --- parts -------------------------------------------------------------------------------

    def _attach_parts(self, seen: set[int]) -> None:
        """(Re)decide the parent of every part seen this frame and of every part without a live parent.

        A part keeps its parent when no candidate is adjacent any more (an opened drawer pulled clear).
        """
        live = {inst.id: inst for inst in self.live()}
        trees: dict[int, cKDTree] = {}
        for inst in live.values():
            allowed = self._parents.get(inst.label)
            if allowed is None:
                continue
            has_parent = inst.parent is not None and inst.parent in live
            if has_parent and inst.id not in seen:
                continue
            best, best_count = None, 0
            points = inst.points()
            for candidate in live.values():
                if candidate.label not in allowed or _is_ancestor(self, inst.id, candidate.id):
                    continue  # (an instance is its own ancestor, so it is never its own parent)
                if candidate.id not in trees:
                    trees[candidate.id] = cKDTree(candidate.points())
                distance, _ = trees[candidate.id].query(points, distance_upper_bound=self.config.part_gap_m)
                count = int(np.isfinite(distance).sum())
                if count > best_count:
                    best, best_count = candidate.id, count
            if best is None and not has_parent and inst.label != "handle":
                best = self._beneath_footprint(inst, [c for c in live.values() if c.label in allowed])
            if best is not None and best != inst.parent:
                self._set_parent(inst, best)

    def _beneath_footprint(self, part: Instance, candidates: list[Instance]) -> int | None:
        """The candidate whose footprint (x, y box, grown by ``part_gap_m``) holds the part's centre,
        nearest first: the parent of a drawer low on a chest of drawers whose carcass shows only
        above and beside the fronts, too far from this drawer for adjacency to find."""
        gap = self.config.part_gap_m
        centre = part.centroid[:2]
        holding = []
        for candidate in candidates:
            if candidate.id == part.id or not len(candidate.keys) or _is_ancestor(self, part.id, candidate.id):
                continue
            lo, hi = candidate.bounds
            if np.all(lo[:2] - gap <= centre) and np.all(centre <= hi[:2] + gap):
                holding.append((float(np.linalg.norm(candidate.centroid[:2] - centre)), candidate.id))
        return min(holding)[1] if holding else None

    def _set_parent(self, inst: Instance, parent_id: int) -> None:
        if inst.parent is not None and inst.parent in self.instances:
            old = self.instances[inst.parent]
            if inst.id in old.children:
                old.children.remove(inst.id)
        inst.parent = parent_id
        parent = self.instances[parent_id]
        if inst.id not in parent.children:
            parent.children.append(inst.id)


def _is_ancestor(memory: InstanceMemory, ancestor: int, of: int) -> bool:
    """Whether ``ancestor`` is ``of`` or above it, so attaching would make a cycle."""
    seen = set()
    current: int | None = of
    while current is not None and current not in seen:
        if current == ancestor:
            return True
        seen.add(current)
        current = memory.instances[current].parent if current in memory.instances else None
    return False


def _bounds(keys: np.ndarray, voxel_m: float) -> tuple[np.ndarray, np.ndarray]:
    pts = centres(keys, voxel_m)
    return pts.min(axis=0) - voxel_m / 2, pts.max(axis=0) + voxel_m / 2


def _box_iou(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> float:
    """IoU of two axis-aligned boxes given as (lo, hi)."""
    inter = np.prod(np.clip(np.minimum(a[1], b[1]) - np.maximum(a[0], b[0]), 0.0, None))
    union_volume = np.prod(a[1] - a[0]) + np.prod(b[1] - b[0]) - inter
    return float(inter / union_volume) if union_volume > 0 else 0.0
