"""Where pieces of one kind of storage were seen, as floor positions, from as far as the camera sees.

The act branch's instance memory (`behaviours.look_inside`) keeps what it saw within 4 m, the range
it opens from, at the 1 cm detail grasping needs. A cabinet glimpsed across a room or through a
doorway is beyond that, yet it is where the robot should go when the question asks what is in it:
without a note of it, exploration only comes back by chance. `Sightings` is that note: for one kind
of storage (and one room, when the question names one), the floor position of every piece seen,
from the pixels each frame labels with that kind, back-projected with their depth.

Pieces are told apart by position alone (centres nearer than ``merge_m`` are one piece), never by
the simulator's per-frame segment ids. Which room a piece stands in is the room its label names:
the world sends that name with every instance (see docs/interactive.md, "What the robot may
know"), as it does for the floors the simulated VLM reads rooms from. Pure: plain arrays in and
out, no bus, no tree.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np

from agent.mapping.camera import back_project
from agent.observation import Observation


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


@dataclass
class Sighting:
    """One piece: its floor position ``xy`` (the mean of every pixel that fell on it, so a nearer,
    larger view counts for more) and ``pixels``, how many did."""

    xy: np.ndarray
    pixels: int


def storage_centres(observation: Observation, kind: str, room: str | None,
                    config: SightingConfig = SightingConfig()) -> list[tuple[np.ndarray, int]]:
    """(floor x, y, pixel count) of each instance this frame labels ``kind`` (standing in ``room``,
    when given), from its pixels with a depth return within ``config.max_depth_m``."""
    found = []
    for label in observation.labels:
        if label.category != kind or (room is not None and label.room != room):
            continue
        mask = (observation.segmentation == label.id) & (observation.depth > 0) \
            & (observation.depth <= config.max_depth_m)
        count = int(np.count_nonzero(mask))
        if count < config.min_pixels:
            continue
        points = back_project(observation.depth, observation.intrinsics, observation.camera_to_world, mask)
        found.append((points[:, :2].mean(axis=0), count))
    return found


class Sightings:
    """Every piece seen so far, in the order first seen."""

    def __init__(self, config: SightingConfig = SightingConfig()) -> None:
        self.config = config
        self.pieces: list[Sighting] = []

    def add(self, centres: Iterable[tuple[np.ndarray, int]]) -> None:
        """Merge a frame's centres (`storage_centres`): into the nearest piece within ``merge_m``,
        as a pixel-weighted mean, else as a new piece."""
        for xy, pixels in centres:
            xy = np.asarray(xy, dtype=float)
            near = [(float(np.linalg.norm(p.xy - xy)), i) for i, p in enumerate(self.pieces)]
            distance, index = min(near, default=(np.inf, -1))
            if distance <= self.config.merge_m:
                piece = self.pieces[index]
                total = piece.pixels + pixels
                piece.xy = (piece.xy * piece.pixels + xy * pixels) / total
                piece.pixels = total
            else:
                self.pieces.append(Sighting(xy, int(pixels)))
