"""Storage pieces placed in a home or on a table: pose, joint states, contents, ids and labels.

A `StoragePlacement` puts one `StorageModel` (frames and conventions: `worlds.storage`) at a pose
with its parts opened as given and small objects in its slots. `home_storage` places every storage
piece of a home and hands its parts and handles their instance ids; `part_labels` and
`home_part_labels` give those links the ground-truth labels a camera sees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from worlds.storage import HANDLE_REACH, StorageModel, yaw_facing

if TYPE_CHECKING:  # homes are made of storage, so only the type is needed here
    from worlds.home import HomeSpec


@dataclass(frozen=True)
class StoragePlacement:
    """One storage piece placed in a scene: where, how open, and which small objects are in which slot.

    ``pose`` is (x, y, z, yaw) of the local origin: z is the top of what it stands on (0 on the
    floor). Instance ids: the carcass keeps ``furniture_id``; part k (in ``model.parts`` order) gets
    ``first_part_id + 2k`` and its handle ``first_part_id + 2k + 1``. ``contents`` pairs an object's
    instance id with the slot it stands in; the object's own centre is where it stands.
    """

    furniture_id: int
    model: StorageModel
    pose: tuple[float, float, float, float]
    first_part_id: int
    states: tuple[tuple[str, float], ...] = ()
    contents: tuple[tuple[int, str], ...] = ()

    def part_ids(self) -> dict[str, int]:
        """Link name (part or handle) -> instance id.

        Returns:
            The ids.
        """
        ids: dict[str, int] = {}
        for k, part in enumerate(self.model.parts):
            ids[part.name], ids[part.handle] = self.first_part_id + 2 * k, self.first_part_id + 2 * k + 1
        return ids

    def state(self, part: str) -> float:
        """A part's joint value in this placement (0, closed, when not given).

        Args:
            part: the part's name.

        Returns:
            The value (rad or m).
        """
        return dict(self.states).get(part, 0.0)

    def slot_spot(self, slot: str, half_height: float, dx: float = 0.0, dy: float = 0.0) -> np.ndarray:
        """World centre of an object ``half_height`` tall standing in ``slot`` at (dx, dy) from its middle.

        A slot in a drawer is taken where the drawer stands in ``states``.

        Args:
            slot: the slot's name.
            half_height: half the object's height.
            dx: the offset across the slot.
            dy: the offset into the slot.

        Returns:
            The centre (3,).
        """
        box = self.model.slot(slot)
        pulled = self.state(box.part) if box.part is not None else 0.0
        cx, cy, cz = box.center
        return self.to_world((cx + dx, cy + dy - pulled, cz - box.size[2] / 2 + half_height))

    def footprint(self) -> tuple[float, float, float, float]:
        """(xmin, ymin, xmax, ymax) in the world around the closed piece and its handles.

        Returns:
            The footprint.
        """
        w, d, _ = self.model.size
        corners = [self.to_world((sx * w / 2, y, 0.0)) for sx in (-1, 1) for y in (-d / 2 - HANDLE_REACH, d / 2)]
        xs, ys = [c[0] for c in corners], [c[1] for c in corners]
        return (min(xs), min(ys), max(xs), max(ys))

    def to_world(self, local: tuple[float, ...] | np.ndarray) -> np.ndarray:
        """Points of the local frame, shape (3,) or (N, 3), in the world.

        Args:
            local: the points.

        Returns:
            The world points, shaped the same.
        """
        x, y, z, yaw = self.pose
        c, s = math.cos(yaw), math.sin(yaw)
        rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        return np.asarray(local, dtype=float) @ rotation.T + np.array([x, y, z])

    def to_dict(self) -> dict[str, Any]:
        """The placement as plain data, for scene specs.

        Returns:
            The dict.
        """
        return {
            "furniture_id": self.furniture_id,
            "model": self.model.to_dict(),
            "pose": list(self.pose),
            "first_part_id": self.first_part_id,
            "states": [list(s) for s in self.states],
            "contents": [list(c) for c in self.contents],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> StoragePlacement:
        """A placement read back from its `to_dict` form.

        Args:
            data: the dict.

        Returns:
            The placement.
        """
        return cls(
            int(data["furniture_id"]),
            StorageModel.from_dict(data["model"]),
            tuple(data["pose"]),
            int(data["first_part_id"]),
            tuple((str(n), float(v)) for n, v in data["states"]),
            tuple((int(i), str(s)) for i, s in data["contents"]),
        )


def part_labels(placement: StoragePlacement, colour: str) -> dict[str, dict[str, Any]]:
    """Link name -> ground-truth label for every part ("door" or "drawer"; flaps are doors) and handle.

    Args:
        placement: the placed piece.
        colour: the piece's colour.

    Returns:
        The labels.
    """
    ids = placement.part_ids()
    labels: dict[str, dict[str, Any]] = {}
    for part in placement.model.parts:
        category = "drawer" if part.kind == "drawer" else "door"
        labels[part.name] = {"id": ids[part.name], "category": category, "colour": colour}
        handle = {"id": ids[part.handle], "category": "handle", "colour": handle_colour(colour)}
        labels[part.handle] = handle
    return labels


def home_storage(home: HomeSpec) -> list[StoragePlacement]:
    """Every storage piece of ``home`` as a placement; parts and handles get ids after every other thing.

    Ids are handed out in furniture order, two per part (the part, then its handle), starting right
    after the largest instance id in the home, so the same home always labels its parts the same.

    Args:
        home: the home.

    Returns:
        The placements, in furniture order.
    """
    things = (*home.rooms, *home.walls, *home.furniture, *home.objects)
    next_id = max((thing.instance_id for thing in things), default=0) + 1
    placements = []
    for piece in home.furniture:
        if piece.storage is None:
            continue
        contents = tuple(
            (item.instance_id, item.slot)
            for item in home.objects
            if item.parent == piece.instance_id and item.relation == "inside" and item.slot is not None
        )
        pose = (piece.center[0], piece.center[1], piece.center[2] - piece.size[2] / 2, yaw_facing(piece.facing))
        states = tuple(sorted(piece.joints.items()))
        placements.append(StoragePlacement(piece.instance_id, piece.storage, pose, next_id, states, contents))
        next_id += 2 * len(piece.storage.parts)
    return placements


def home_part_labels(home: HomeSpec) -> dict[int, dict[str, Any]]:
    """Instance id -> label of every storage part and handle in ``home`` (the ids `home_storage` hands out).

    Args:
        home: the home.

    Returns:
        The labels by id.
    """
    colours = {piece.instance_id: piece.colour for piece in home.furniture}
    return {
        label["id"]: label
        for placement in home_storage(home)
        for label in part_labels(placement, colours[placement.furniture_id]).values()
    }


def handle_colour(colour: str) -> str:
    """Handles are black, except on black furniture where they are white: they must stand out.

    Args:
        colour: the furniture's colour.

    Returns:
        The handles' colour.
    """
    return "white" if colour == "black" else "black"
