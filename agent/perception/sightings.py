"""Where pieces of one kind of storage were seen, as floor positions, from as far as the camera sees,
and which room each seemed to stand in.

The act branch's instance memory (`behaviours.look_inside`) keeps what it saw within 4 m, the range
it opens from, at the 1 cm detail grasping needs. A cabinet glimpsed across a room or through a
doorway is beyond that, yet it is where the robot should go when the question asks what is in it:
without a note of it, exploration only comes back by chance. `Sightings` is that note: for one kind
of storage, the floor position of every piece seen, from the pixels each frame labels with that
kind, back-projected with their depth.

Pieces are told apart by position alone (centres nearer than ``merge_m`` are one piece), never by
the simulator's per-frame segment ids. Which room a piece stands in is what the frames showed
around it (`agent.perception.rooms`: a toilet beside it, a bathroom), summed over every frame that
saw it; no label names a room. Pure: plain arrays in and out, no bus, no tree.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from agent.mapping.camera import back_project
from agent.observation import Observation
from agent.perception.rooms import read_rooms


@dataclass(frozen=True)
class SightingConfig:
    """``max_depth_m``: pixels farther than this are not trusted for a position; ``min_pixels``:
    fewer pixels of a piece than this in a frame say too little; ``merge_m``: two sightings whose
    centres are nearer than this are the same piece (pieces stand side by side at least their
    width apart, 0.45 m for a nightstand, and a far view places a centre within a few decimetres)."""

    max_depth_m: float = 8.0
    min_pixels: int = 30
    merge_m: float = 0.8

    def __post_init__(self) -> None:
        for name in ("max_depth_m", "merge_m"):
            if not getattr(self, name) > 0:
                raise ValueError(f"act.approach.sightings.{name}: {getattr(self, name)} must be positive")
        if self.min_pixels < 1:
            raise ValueError(f"act.approach.sightings.min_pixels: {self.min_pixels} must be at least 1")


@dataclass(frozen=True)
class Centre:
    """A piece of storage in one frame: its floor position ``xy``, the ``pixels`` it filled, and
    the room kind the frame shows it standing in (None when nothing in view tells)."""

    xy: np.ndarray
    pixels: int
    room: str | None


@dataclass
class Sighting:
    """One piece: its floor position ``xy`` (the mean of every pixel that fell on it, so a nearer,
    larger view counts for more), ``pixels``, how many did, and ``rooms``: room kind -> pixels
    of the frames that showed it standing in a room of that kind."""

    xy: np.ndarray
    pixels: int
    rooms: dict[str, int] = field(default_factory=dict)

    @property
    def room(self) -> str | None:
        """The room kind most of the frames that told one showed it in; None when none told."""
        return max(sorted(self.rooms), key=self.rooms.__getitem__, default=None)


def storage_centres(observation: Observation, kind: str, config: SightingConfig = SightingConfig()) -> list[Centre]:
    """Each instance this frame labels ``kind``, from its pixels with a depth return within
    ``config.max_depth_m``, with the room the frame shows it in.

    Args:
        observation: the frame.
        kind: the storage category.
        config: the farthest return used, and the pixels a centre needs.

    Returns:
        The centres.
    """
    found = []
    reading = None
    for label in observation.labels:
        if label.category != kind:
            continue
        mask = (observation.segmentation == label.id) & (observation.depth > 0) \
            & (observation.depth <= config.max_depth_m)
        count = int(np.count_nonzero(mask))
        if count < config.min_pixels:
            continue
        reading = reading or read_rooms(observation)
        points = back_project(observation.depth, observation.intrinsics, observation.camera_to_world, mask)
        found.append(Centre(points[:, :2].mean(axis=0), count, reading.room_of(label.id)))
    return found


class Sightings:
    """Every piece seen so far, in the order first seen.

    Args:
        config: how near a centre merges into a piece.
    """

    def __init__(self, config: SightingConfig = SightingConfig()) -> None:
        self.config = config
        self.pieces: list[Sighting] = []

    def add(self, centres: Iterable[Centre]) -> None:
        """Merge a frame's centres (`storage_centres`): into the nearest piece within ``merge_m``,
        as a pixel-weighted mean, else as a new piece; the room each was seen in is tallied.

        Args:
            centres: a frame's centres.
        """
        for centre in centres:
            xy = np.asarray(centre.xy, dtype=float)
            near = [(float(np.linalg.norm(p.xy - xy)), i) for i, p in enumerate(self.pieces)]
            distance, index = min(near, default=(np.inf, -1))
            if distance <= self.config.merge_m:
                piece = self.pieces[index]
                total = piece.pixels + centre.pixels
                piece.xy = (piece.xy * piece.pixels + xy * centre.pixels) / total
                piece.pixels = total
            else:
                piece = Sighting(xy, int(centre.pixels))
                self.pieces.append(piece)
            if centre.room is not None:
                piece.rooms[centre.room] = piece.rooms.get(centre.room, 0) + int(centre.pixels)
