"""Which room each part of a frame shows, read off what stands there: a bed makes a bedroom.

No camera sees a room's name, and the world sends none (`agent.observation.InstanceLabel`). A
person tells a kitchen by its stove and a bathroom by its toilet; this module does the same with a
frame's instance segmentation and depth, and nothing else:

1. **Footing.** A thing stands on whatever its bottom edge meets in the image at the same depth
   (within ``contact_m``): the pixel just below its lowest pixels in each column. A mug's bottom
   meets the counter it stands on, the counter's the floor. A thing whose bottom edge meets
   something much nearer (an occluder) or farther (a background) has no footing in view.
2. **Regions.** Following the footing from thing to thing ends at a floor, or at a thing whose own
   footing is out of view; that end is the thing's region. Floors are separate instances per
   room (each room's floor is tinted its own colour, so any segmenter splits them), so a region
   ending at a floor is one room's floor and what stands on it. When the frame shows a single
   floor, or none, the whole frame is taken for one room: every region is merged into it.
3. **Cues.** Each region's furniture and fixtures (`commonsense.room_named_by`: a bed, a toilet, a
   stove; small things are carried about and say nothing) name its room kind; the strongest cue
   wins. A region without a strong enough cue is a room of unknown kind.

Only the room's kind shows, never which of two bedrooms it is. The reading is deterministic; the
simulated VLM adds its own misjudgements on top (`agent.vlm.sim`). Pure: plain arrays in and out.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

import numpy as np

from agent.mapping.camera import back_project
from agent.observation import Observation
from agent.vlm import commonsense

#: Labels of things that belong to no room: walls stand between rooms, so nothing stands on one.
_NO_ROOM = ("wall",)
#: Footing is followed through at most this many things (a ring in a box on a shelf on a floor).
_MAX_CHAIN = 6
#: Every this many rows and columns of a floor's pixels are back-projected (`floor_points`).
_PIXEL_STRIDE = 2


@dataclass(frozen=True)
class RoomReadingConfig:
    """``contact_m``: the depth step, in metres, across which a thing's bottom edge still meets
    what is below it (a mug and the counter top just in front of it; one pixel row spans about
    0.1 m of floor at 5 m); ``min_cue_px``: pixels a piece of furniture must fill to be read as a
    cue (a sliver of a bed at the frame's edge is not yet a bed)."""

    contact_m: float = 0.3
    min_cue_px: int = 40

    def __post_init__(self) -> None:
        if not self.contact_m > 0:
            raise ValueError(f"rooms.contact_m: {self.contact_m} must be positive")
        if self.min_cue_px < 1:
            raise ValueError(f"rooms.min_cue_px: {self.min_cue_px} must be at least 1")


@dataclass(frozen=True)
class Cue:
    """A thing in view that says which room kind its region is, and how strongly (an affinity)."""

    instance: int
    kind: str
    strength: float


@dataclass(frozen=True)
class RoomReading:
    """A frame read for rooms. ``region``: instance id -> its region (a floor's id, or the id of
    the thing at the end of its footing); ``floors``: the floor ids in view; ``cues``: region ->
    its cues, strongest first."""

    region: dict[int, int]
    floors: frozenset[int]
    cues: dict[int, tuple[Cue, ...]]

    def kind(self, region: int, ignoring: Collection[int] = ()) -> str | None:
        """The room kind a region shows, from its strongest cue other than the things ``ignoring``
        (the thing a question asks about is no cue for its own room: a tv says 'living room' but
        may stand in a bedroom); None when nothing tells.

        Args:
            region: the region.
            ignoring: instances whose cue does not count.

        Returns:
            The room kind, or None.
        """
        return next((cue.kind for cue in self.cues.get(region, ()) if cue.instance not in ignoring), None)

    def room_of(self, instance: int, ignoring: Collection[int] = ()) -> str | None:
        """The room kind the thing stands in, as far as the frame tells (`kind`).

        Args:
            instance: the thing's segmentation id.
            ignoring: instances whose cue does not count.

        Returns:
            The room kind, or None.
        """
        region = self.region.get(instance)
        return None if region is None else self.kind(region, ignoring)


def read_rooms(observation: Observation, config: RoomReadingConfig = RoomReadingConfig()) -> RoomReading:
    """Read which room each instance of the frame stands in (see the module docstring).

    Args:
        observation: the frame.
        config: how near a thing must be to stand on a floor.

    Returns:
        The reading.
    """
    categories = {label.id: label.category for label in observation.labels}
    floors = frozenset(i for i, category in categories.items() if category == "floor")
    footing = _footing(observation, categories, config.contact_m)
    region = {}
    for instance, category in categories.items():
        if category not in _NO_ROOM:
            region[instance] = _end_of_footing(instance, footing, floors)
    if len(floors) <= 1:  # one floor or none in view: one room
        whole = next(iter(floors), min(region.values(), default=-1))
        region = {instance: whole for instance in region}
    areas = _pixel_counts(observation.segmentation)
    cues: dict[int, list[Cue]] = {}
    for instance, where in region.items():
        named = commonsense.room_named_by(categories[instance])
        if named is not None and areas.get(instance, 0) >= config.min_cue_px:
            cues.setdefault(where, []).append(Cue(instance, *named))
    ordered = {where: tuple(sorted(found, key=lambda cue: (-cue.strength, cue.instance)))
               for where, found in cues.items()}
    return RoomReading(region, floors, ordered)


def floor_points(observation: Observation, reading: RoomReading, kind: str, max_depth_m: float) -> np.ndarray:
    """Floor points (N, 2), up to ``max_depth_m`` away, of the frame's floors read as rooms of ``kind``.

    Args:
        observation: the frame.
        reading: the frame's `read_rooms`.
        kind: the room kind.
        max_depth_m: the farthest floor point kept.

    Returns:
        The points (world x, y).
    """
    ids = [floor for floor in reading.floors if reading.kind(floor) == kind]
    if not ids:
        return np.zeros((0, 2))
    mask = np.zeros(observation.segmentation.shape, dtype=bool)
    mask[::_PIXEL_STRIDE, ::_PIXEL_STRIDE] = True
    mask &= np.isin(observation.segmentation, ids) & (observation.depth > 0) & (observation.depth <= max_depth_m)
    return back_project(observation.depth, observation.intrinsics, observation.camera_to_world, mask)[:, :2]


def floor_points_by_kind(observation: Observation, reading: RoomReading, max_depth_m: float) -> dict[str, np.ndarray]:
    """`floor_points` of every room kind ``reading`` (the frame's `read_rooms`) tells.

    Args:
        observation: the frame.
        reading: the frame's `read_rooms`.
        max_depth_m: the farthest floor point kept.

    Returns:
        The points by room kind.
    """
    kinds = {kind for floor in reading.floors if (kind := reading.kind(floor)) is not None}
    return {kind: floor_points(observation, reading, kind, max_depth_m) for kind in sorted(kinds)}


def _footing(observation: Observation, categories: dict[int, str], contact_m: float) -> dict[int, int]:
    """Instance -> what most of its bottom edge meets at the same depth (floors and walls stand on
    nothing, and nothing stands on a wall)."""
    seg, depth = observation.segmentation, observation.depth
    upper, lower = seg[:-1], seg[1:]
    meets = ((upper != lower) & (upper >= 0) & (lower >= 0) & (depth[:-1] > 0) & (depth[1:] > 0)
             & (np.abs(depth[:-1] - depth[1:]) <= contact_m))
    pairs = np.stack([upper[meets], lower[meets]], axis=1).astype(np.int64)
    if pairs.size == 0:
        return {}
    found, counts = np.unique(pairs, axis=0, return_counts=True)
    best: dict[int, tuple[int, int]] = {}
    for (thing, below), count in zip(found.tolist(), counts.tolist()):
        if categories.get(thing) in ("floor", *_NO_ROOM) or categories.get(below) in _NO_ROOM:
            continue
        if count > best.get(thing, (0, -1))[0]:
            best[thing] = (count, below)
    return {thing: below for thing, (_, below) in best.items()}


def _end_of_footing(instance: int, footing: dict[int, int], floors: frozenset[int]) -> int:
    """The floor the thing stands on through what it stands on, or the last thing whose footing is
    out of view (a loop of footings, from a thin seam, ends where it closes)."""
    seen = [instance]
    current = instance
    for _ in range(_MAX_CHAIN):
        if current in floors or current not in footing or footing[current] in seen:
            break
        current = footing[current]
        seen.append(current)
    return current


def _pixel_counts(segmentation: np.ndarray) -> dict[int, int]:
    ids, counts = np.unique(segmentation[segmentation >= 0], return_counts=True)
    return dict(zip(ids.tolist(), counts.tolist()))
