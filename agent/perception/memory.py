"""Instance memory across views: RoboEXP's low-level memory (§IV, Memory Module) as voxel sets.

Each frame is cut into detections (`agent.perception.frames`), and each detection either merges
with a remembered instance or becomes a new one: the labels must agree and the geometry overlap
(`agent.perception.overlap`). The simulator's segmentation ids are never used to match: they are
per-frame segments, kept only as ``hint``. Before a frame is merged, the voxels it shows are no
longer there are forgotten (`agent.perception.staleness`); an instance left with no voxels is
marked gone. A thing that moved reappears as a new instance wherever it no longer overlaps its old
voxels (a cup picked away); the memory does not guess that it is the same thing, and a caller that
knows (the skill that moved it) says so with `InstanceMemory.merge` or, beforehand,
`InstanceMemory.move`, which for a thing carried also says where it now stands. A door swung open
usually keeps its identity by itself: the strip along its hinge is hidden behind the open door, not
stale, and the open door overlaps it. Parts (handles, doors, drawers) are attached to a parent
(`agent.perception.part_parents`).
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import replace
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from agent.mapping.camera import Intrinsics
from agent.perception.frames import Detection, check_frame, check_labels, detect, frame_labels
from agent.perception.instances import FrameUpdate, Instance, MemoryConfig, family_bounds
from agent.perception.overlap import box_of, overlap, share_within
from agent.perception.part_parents import attach_parts, set_parent
from agent.perception.staleness import DepthView, depth_view, stale_voxels
from agent.perception.voxels import centres, pack, union, voxel_indices

#: A detection matching nothing is a thing a caller moved (`InstanceMemory.move`) and has not seen
#: since where it covers this share of the smaller of its footprint and the one the thing was moved to.
MOVED_SHARE = 0.5


class InstanceMemory:
    """Instances fused over frames; see the module docstring for the rules.

    Args:
        config: the memory's thresholds.
    """

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
        """The instances still there.

        Returns:
            Instances not gone, by id.
        """
        return [inst for _, inst in sorted(self.instances.items()) if not inst.gone]

    def get(self, instance_id: int) -> Instance:
        """The instance an id names now, even after it was absorbed into another.

        Args:
            instance_id: an id the memory gave out.

        Returns:
            The instance, following aliases of absorbed ids.

        Raises:
            KeyError: the memory never gave out ``instance_id``.
        """
        while instance_id in self.aliases:
            instance_id = self.aliases[instance_id]
        try:
            return self.instances[instance_id]
        except KeyError:
            raise KeyError(f"instance_id: {instance_id} is not in the memory") from None

    def with_label(self, label: str) -> list[Instance]:
        """The live instances of one category.

        Args:
            label: the category.

        Returns:
            Live instances labelled ``label``, by id.
        """
        return [inst for inst in self.live() if inst.label == label]

    # --- writing -----------------------------------------------------------------------------

    def integrate(self, observation: Any) -> FrameUpdate:
        """Fold in one observation, as `integrate_frame` does.

        Args:
            observation: an `agent.observation.Observation` (or anything with the same fields).

        Returns:
            What the frame changed.
        """
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

        Args:
            depth: (H, W) linear metres with 0 = no return.
            segmentation: (H, W) per-frame instance ids, -1 = nothing.
            labels: the label per id (see `frames.frame_labels`).
            intrinsics: the camera's intrinsics.
            camera_to_world: 4x4 with OpenCV camera axes (x right, y down, z ahead).

        Returns:
            What the frame changed.

        Raises:
            ValueError: a malformed frame, refused before it changes anything.
        """
        cfg = self.config
        check_frame(depth, segmentation, intrinsics, camera_to_world)
        parsed = frame_labels(labels)
        check_labels(segmentation, parsed)  # a bad frame is refused before it changes anything
        self.frame += 1
        view = depth_view(np.asarray(depth, dtype=float), np.asarray(segmentation), parsed, intrinsics,
                          np.asarray(camera_to_world, dtype=float), cfg.no_return_is_free)
        shrunk, gone = self._forget_stale(view)
        detections = detect(depth, segmentation, parsed, intrinsics, camera_to_world,
                            cfg.voxel_m, cfg.min_pixels, cfg.max_depth_m)
        created, updated, absorbed = [], [], {}
        for detection in detections:
            matches = self._matches(detection)
            moved = None if matches else self._moved_here(detection)
            if moved is not None:  # its voxels were the caller's guess, and the view disagrees
                moved.keys, moved.hits = moved.keys[:0], moved.hits[:0]
                if moved.gone:
                    self._revive(moved)
                    gone.remove(moved.id)
                matches = [moved.id]
            if not matches:
                created.append(self._create(detection).id)
                continue
            target = self.instances[self._oldest_together(matches)]
            apart = []
            for other in (m for m in matches if m != target.id):
                if self.instances[other].frames & (target.frames | {self.frame}):
                    apart.append(other)  # seen apart in one frame: two things, however close (stacked drawers)
                    continue
                absorbed[other] = target.id
                self._absorb_instance(target, self.instances[other])
            # Those seen apart before, and not in this frame (which shows them apart from this
            # detection), share the detection: one that spans two drawers is both, not the first.
            sharing = [target] + [self.instances[i] for i in apart if self.frame not in self.instances[i].frames]
            for inst, share in _shares(detection, sharing):
                self._absorb_detection(inst, share)
                updated.append(inst.id)
        seen = set(created) | set(updated)
        attach_parts(self.instances, self.live(), seen, self._parents, self.config.part_gap_m)
        return FrameUpdate(self.frame, tuple(created), tuple(i for i in updated if i not in created),
                           shrunk, tuple(gone), absorbed)

    def _oldest_together(self, matches: list[int]) -> int:
        """Of the instances a detection matches, best first, the oldest one not seen apart from the
        best (in one frame with it): the one the others are merged into, so that a thing keeps the
        identity it was first known by (the box picked away, seen anew where it was put down, is
        still that box and not a new one that absorbed it)."""
        best = self.instances[matches[0]]
        together = [m for m in matches if m == best.id or not self.instances[m].frames & (best.frames | {self.frame})]
        return min(together, key=lambda m: self.instances[m].first_seen)

    def merge(self, keep: int, other: int) -> Instance:
        """Declare ``other`` the same thing as ``keep``, for callers who know what perception cannot
        (the door just opened is the door that was closed).

        Voxels and children move over, ``other`` becomes an alias of ``keep``. Either may be gone;
        the result is live if it has voxels.

        Args:
            keep: the id that lives on.
            other: the id absorbed into it.

        Returns:
            The merged instance.

        Raises:
            ValueError: the two have different labels.
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
            self._revive(target)
        return target

    def _revive(self, inst: Instance) -> None:
        """Mark a gone ``inst`` live again, back among its parent's children."""
        inst.gone, inst.gone_frame = False, None
        if inst.parent is not None and inst.parent in self.instances:
            set_parent(self.instances, inst, inst.parent)

    def move(self, instance_id: int, motion: np.ndarray, carried: bool = False) -> list[int]:
        """Carry an instance and its parts (children, recursively) by a rigid motion.

        For the caller that moved the thing and knows how (a skill that pulled a drawer out by
        0.2 m, put a cup down elsewhere): the next view then finds it where it now is and merges
        with it, instead of reporting a new thing there and the old one gone. Voxel centres are
        moved and quantised again; voxels landing in one keep the sum of their hits.

        Args:
            instance_id: the instance moved.
            motion: 4x4 world-frame transform, applied on the left.
            carried: the thing was lifted, carried and put down (not slid or turned on a joint,
                where it stays one with its piece): until it is seen again, a detection of its
                label standing where it was put is it, however far the motion, as the caller
                guessed it, left its voxels from it (`_moved_here`).

        Returns:
            The ids moved.

        Raises:
            ValueError: ``motion`` is not a finite 4x4 transform.
        """
        motion = np.asarray(motion, dtype=float)
        if motion.shape != (4, 4) or not np.all(np.isfinite(motion)):
            raise ValueError(f"motion: a finite 4x4 transform is needed, got shape {motion.shape}")
        root = self.get(instance_id)
        moved, todo = [], [root.id]
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
        if carried and len(root.keys):
            lo, hi = root.bounds
            root.moved_to = np.array([lo[:2], hi[:2]])
        return moved

    # --- stale voxels ------------------------------------------------------------------------

    def _forget_stale(self, view: DepthView) -> tuple[dict[int, int], list[int]]:
        """Delete voxels the frame looks through; returns (id -> voxels removed, ids now gone)."""
        cfg = self.config
        shrunk: dict[int, int] = {}
        gone: list[int] = []
        for inst in self.live():
            stale = stale_voxels(view, inst, cfg.stale_margin_m, cfg.stale_majority)
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
        live = {inst.id: inst for inst in self.live() if len(inst.keys)}
        for inst in live.values():
            if inst.label != detection.label:
                continue
            score = overlap(detection, inst, self.config, family_bounds(inst, live))
            if score > 0:
                scored.append((-score, inst.id))
        return [i for _, i in sorted(scored)]

    def _moved_here(self, detection: Detection) -> Instance | None:
        """The instance of the detection's label that a caller moved to where the detection stands
        (`move`) and that has not been seen since, for a detection that matches nothing.

        A move carries the thing's voxels by the motion the caller planned, which is only as good
        as what the caller knew of the thing: a box whose bottom was hidden in a drawer, or taken
        as 25 cm tall where it is 9 cm, put down by where its top was to go, left its voxels in
        the air above it or half inside it. The next view looks through them, they all go, and the
        box was a new thing there, while the box picked away was gone: its pick back found no route
        that kept off the box itself (recursive 1178 and 1261 of tuning-wide). Where the
        detection's footprint shares `MOVED_SHARE` of the smaller of the two with the footprint the
        thing was moved to, it is that thing, live or gone in this frame (the one sharing most),
        and what the view shows of it replaces the voxels the move guessed.
        """
        lo, hi = box_of(detection.keys, self.config.voxel_m)
        best, best_share = None, MOVED_SHARE
        for inst in self.instances.values():
            if inst.label != detection.label or inst.moved_to is None or (inst.gone and inst.gone_frame != self.frame):
                continue
            seen, put = (lo[:2], hi[:2]), (inst.moved_to[0], inst.moved_to[1])
            share = max(share_within(seen, put), share_within(put, seen))  # of the smaller of the two
            if share >= best_share:
                best, best_share = inst, share
        return best

    def _create(self, detection: Detection) -> Instance:
        inst = Instance(self._next_id, detection.label, detection.colour, detection.keys, detection.hits,
                        self.config.voxel_m, self.frame, self.frame, detection.hint, {self.frame})
        self.instances[inst.id] = inst
        self._next_id += 1
        return inst

    def _absorb_detection(self, inst: Instance, detection: Detection) -> None:
        inst.keys, inst.hits = union(inst.keys, inst.hits, detection.keys, detection.hits)
        inst.last_seen = self.frame
        inst.moved_to = None  # seen where it is
        if detection.hint >= 0:
            inst.hint = detection.hint
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
            set_parent(self.instances, target, other.parent)
        del self.instances[other.id]
        self.aliases[other.id] = target.id


def _shares(detection: Detection, instances: list[Instance]) -> list[tuple[Instance, Detection]]:
    """``detection`` cut among ``instances``: each voxel to the instance whose nearest voxel is nearest.

    A detection that spans things the memory knows to be apart (two stacked drawers a detector took
    for one) would otherwise go whole to the first, whose voxels then cover the other too, so every
    later view of the other matches the first: a ghost never updated again. Cut, each keeps its own.
    A share names no segment (hint -1): the detection's segment was all of them at once.

    Args:
        detection: the frame's detection.
        instances: the instances it matched that are known to be apart, the best match first.

    Returns:
        (instance, its share) for each instance given at least one voxel; the detection whole
        when there is only one instance.
    """
    if len(instances) == 1:
        return [(instances[0], detection)]
    points = centres(detection.keys, instances[0].voxel_m)
    distances = np.stack([cKDTree(inst.points()).query(points)[0] for inst in instances])
    nearest = np.argmin(distances, axis=0)  # ties go to the best match
    shares = []
    for k, inst in enumerate(instances):
        mine = nearest == k
        if mine.any():
            hits = detection.hits[mine]
            shares.append((inst, replace(detection, hint=-1, keys=detection.keys[mine], hits=hits,
                                         pixels=int(hits.sum()))))
    return shares
