"""Setting a scene in a PyBullet client: a home or a tabletop and the robot, built from scratch.

A `Stage` is what one build made, whole from the start: the scene's bodies and labels, the floors
the robot stands on, the home's facts, storage parts by instance id, and what rides on what
(`worlds.riders`). Small objects are static bodies, so an object standing in a drawer is moved by
the drawer's displacement whenever the drawer moves.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pybullet as p

from worlds.body import RobotBody
from worlds.camera import SegLabels
from worlds.facts import HomeFacts
from worlds.home import HomeSpec
from worlds.riders import Riders
from worlds.robot import CameraConfig
from worlds.scene import BuiltScene, StorageBody, build_scene, floor_bodies, link_indices
from worlds.tabletop import build_tabletop
from worlds.tabletop_scene import TabletopScene
from worlds.things import Label


@dataclass(frozen=True)
class Stage:
    """One built scene and what is known about its bodies.

    Args:
        client: the PyBullet client it is built in.
        built: its labels, small objects' bodies and storage pieces.
        riders: what each small object rides on.
        floors: the bodies the robot stands on, never obstacles (none on a tabletop).
        facts: the home's facts; None for a tabletop, whose things have no switches.
        parts: a storage part's instance id -> (its piece's instance id, its name).
    """

    client: int
    built: BuiltScene
    riders: Riders
    floors: set[int] = field(default_factory=set)
    facts: HomeFacts | None = None
    parts: dict[int, tuple[int, str]] = field(default_factory=dict)

    def label(self, body: int, link: int) -> Label:
        """What the camera calls a body's link: its own label, else its body's.

        Args:
            body: a body of the scene.
            link: one of its links (-1 for the base).

        Returns:
            The label, as a frame carries it.
        """
        labels = self.built.labels
        return labels.get((body, link), labels[(body, -1)])

    def label_of(self, body: int, link: int) -> Label:
        """The label of a body's link, with ``link`` naming a storage piece's part or handle.

        Args:
            body: a body of the scene.
            link: one of its links (-1 for the base).

        Returns:
            `label`'s label plus ``link``: the part's or handle's name, else None.
        """
        name = None
        for piece in self.built.storage.values():
            if piece.body == body:
                name = next((n for n, index in piece.links.items() if index == link), None)
        return {**self.label(body, link), "link": name}

    def item_of(self, body: int) -> int:
        """The instance id of the small object that ``body`` is.

        Args:
            body: a small object's body.

        Returns:
            Its instance id.
        """
        return next(item for item, b in self.built.items.items() if b == body)


def set_stage(client: int, scene: HomeSpec | TabletopScene, camera: CameraConfig) -> tuple[Stage, RobotBody]:
    """Replace everything in ``client`` with a home (its storage furniture articulated) or a
    tabletop, and the robot.

    Args:
        client: the PyBullet client.
        scene: the home or the tabletop to build.
        camera: the head camera the robot carries.

    Returns:
        The new stage, and the robot at the origin with its arm stowed, holding every storage
        part's joint limits as end stops.
    """
    p.resetSimulation(physicsClientId=client)
    home = scene if isinstance(scene, HomeSpec) else None
    if home is not None:
        built = build_scene(home, client)
    else:
        built = _tabletop_built(client, scene, build_tabletop(client, scene))
    body = RobotBody(client, camera)
    for piece in built.storage.values():
        body.arm.end_stops.add(piece.body)
    riders = Riders(client, built, {thing.instance_id: thing.parent for thing in scene.objects})
    if home is None:
        return Stage(client, built, riders), body
    parts = {piece.placement.part_ids()[part.name]: (piece_id, part.name)
             for piece_id, piece in built.storage.items() for part in piece.placement.model.parts}
    return Stage(client, built, riders, floor_bodies(built.labels), HomeFacts(home), parts), body


def _tabletop_built(client: int, scene: TabletopScene, labels: SegLabels) -> BuiltScene:
    """The storage pieces and small objects among a built tabletop's ``labels``."""
    placements = {placement.furniture_id: placement for _, placement in scene.storage}
    objects = {obj.instance_id for obj in scene.objects}
    built = BuiltScene(labels)
    for (body, link), label in labels.items():
        if link == -1 and label["id"] in placements:
            built.storage[label["id"]] = StorageBody(body, placements[label["id"]], link_indices(client, body))
        elif link == -1 and label["id"] in objects:
            built.items[label["id"]] = body
    return built
