"""What the instance memory is made of: remembered instances, a frame's diff, and the thresholds.

`agent.perception.memory.InstanceMemory` fuses frames into `Instance` records under the rules of a
`MemoryConfig`, and reports each frame's changes as a `FrameUpdate`, the diff the ACSG needs.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from agent.perception.voxels import centres

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
    before its unconfirmed rest is cleared too (see `agent.perception.staleness.stale_voxels`).
    ``part_gap_m`` 5 cm: a handle's bar stands 3.5 cm proud of its front on posts the camera
    rarely sees, so from straight ahead only the bar's face, 4.3 cm out, is in memory.
    ``no_return_is_free``: whether a pixel without a depth return (0) counts as seeing through to
    infinity (true in simulation, where 0 means "beyond the far plane") or as seeing nothing.

    Raises:
        ValueError: a length is not positive, or a share lies outside (0, 1].
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
    ``moved_to``: see `InstanceMemory.move`.
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
    #: (2, 2) the (x, y) box a caller carried the instance to (`InstanceMemory.move`), until it is
    #: seen again: where a detection of its label stands, it is this thing.
    moved_to: np.ndarray | None = None

    @property
    def voxel_count(self) -> int:
        """How many voxels the instance holds."""
        return int(len(self.keys))

    def points(self, min_hits: int = 1) -> np.ndarray:
        """The instance's voxels as points, for geometry that works on point sets.

        Args:
            min_hits: keep only voxels seen at least this often (1 keeps all).

        Returns:
            (N, 3) voxel centres, world frame.
        """
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


def family_bounds(inst: Instance, live: Mapping[int, Instance]) -> tuple[np.ndarray, np.ndarray]:
    """The box around an instance and its live parts, recursively (a piece with its doors and drawers).

    Args:
        inst: the instance.
        live: the live instances by id (parts not among them are left out).

    Returns:
        (lo, hi) corners.
    """
    los, his, todo, seen = [], [], [inst], set()
    while todo:
        current = todo.pop()
        if current.id in seen:
            continue
        seen.add(current.id)
        lo, hi = current.bounds
        los.append(lo)
        his.append(hi)
        todo.extend(live[child] for child in current.children if child in live)
    return np.min(los, axis=0), np.max(his, axis=0)


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
