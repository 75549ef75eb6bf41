"""What the simulated VLM takes in from one frame: the things it notices, and the room it takes
each part of the frame for.

Both come from the frame alone. What is in view, how large and how far, comes from the instance
segmentation and depth with the labels of the instances in the frame; which room a part of the
frame shows is read off the furniture standing there (`agent.perception.rooms`), and misjudged
now and then. Every draw comes from the generator the caller passes, in a fixed order, so one
question about one frame always gets the same reading.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass

import numpy as np

from agent.observation import InstanceLabel, Observation
from agent.perception.rooms import read_rooms
from agent.vlm.sim_params import SimParams
from worlds.vocabulary import ROOM_TYPES


@dataclass(frozen=True)
class Seen:
    """An instance of the frame: its label, pixel area and mean depth (m)."""

    label: InstanceLabel
    area_px: int
    distance_m: float


class FrameTake:
    """One frame as the model takes it in for one question: `seen` lists every labelled instance,
    `noticed` draws which of some of them the model notices, `room_of` says which room kind it
    takes a thing to stand in (None when nothing in view tells).

    Args:
        observation: the frame.
        params: the simulated model's parameters.
        rng: the draws' generator (the misjudged rooms are drawn here).
    """

    def __init__(self, observation: Observation, params: SimParams, rng: np.random.Generator) -> None:
        self.observation = observation
        self.params = params
        self.seen = _sightings(observation)
        self.rooms = read_rooms(observation)
        self._rng = rng
        # Misjudged rooms are drawn first, one pair of draws per region, so that what is asked
        # afterwards (and in which order) changes none of them.
        regions = sorted(set(self.rooms.region.values()) | self.rooms.floors)
        draws = [(rng.random() < params.room_error, int(rng.integers(1, len(ROOM_TYPES)))) for _ in regions]
        self._misjudged = {region: shift for region, (wrong, shift) in zip(regions, draws) if wrong}

    def noticed(self, fits: Callable[[InstanceLabel], bool]) -> list[Seen]:
        """The instances that fit which the model notices: each with probability ``skill`` times
        a size term (1 − exp(−area/notice_area_px)) times a distance term (exp(−max(0, d −
        notice_near_m)/notice_distance_m)). One draw per instance in the frame, fitting or not.

        Args:
            fits: which instances count.

        Returns:
            The noticed instances.
        """
        p = self.params
        kept = []
        for seen in self.seen:
            size = 1.0 - np.exp(-seen.area_px / p.notice_area_px)
            far = max(0.0, seen.distance_m - p.notice_near_m)
            chance = p.skill * size * np.exp(-far / max(p.notice_distance_m, 1e-9))
            if self._rng.random() < chance and fits(seen.label):
                kept.append(seen)
        return kept

    def region_kind(self, region: int, ignoring: Collection[int] = ()) -> str | None:
        """The room kind the model takes a region for: what its cues say (`RoomReading.kind`),
        replaced by another kind when this region is one it misjudges (``room_error``).

        Args:
            region: the region.
            ignoring: instances whose cue does not count.

        Returns:
            The room kind, or None.
        """
        kind = self.rooms.kind(region, ignoring)
        if kind is None or region not in self._misjudged:
            return kind
        return ROOM_TYPES[(ROOM_TYPES.index(kind) + self._misjudged[region]) % len(ROOM_TYPES)]

    def room_of(self, instance: int, ignoring: Collection[int] = ()) -> str | None:
        """The room kind the model takes the thing to stand in (`region_kind` of its region).

        Args:
            instance: the thing's segmentation id.
            ignoring: instances whose cue does not count.

        Returns:
            The room kind, or None.
        """
        region = self.rooms.region.get(instance)
        return None if region is None else self.region_kind(region, ignoring)

    def room_share(self, kind: str) -> float:
        """The share of the image filled by the parts the model takes for a room of ``kind``.

        Args:
            kind: the room kind.

        Returns:
            The share (0 to 1).
        """
        ids = [instance for instance in self.rooms.region if self.room_of(instance) == kind]
        return float(np.isin(self.observation.segmentation, ids).mean()) if ids else 0.0

    def floor_at_feet(self) -> int | None:
        """The floor instance filling the bottom middle of the image: where the robot stands.

        Returns:
            The floor's segmentation id, or None.
        """
        height, width = self.observation.segmentation.shape
        patch = self.observation.segmentation[int(height * 0.85):, width // 3: 2 * width // 3].ravel().tolist()
        under = [i for i in patch if i in self.rooms.floors]
        return max(set(under), key=under.count) if under else None


def _sightings(observation: Observation) -> list[Seen]:
    """Each labelled instance with its pixel area and mean depth in this frame."""
    seg = observation.segmentation.ravel()
    depth = observation.depth.ravel()
    ids, inverse, counts = np.unique(seg, return_inverse=True, return_counts=True)
    depth_sums = np.bincount(inverse, weights=depth)
    stats = {int(i): (int(n), float(s / n)) for i, n, s in zip(ids, counts, depth_sums)}
    return [Seen(label, *stats[label.id]) for label in observation.labels if label.id in stats]
