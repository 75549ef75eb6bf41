"""What small objects ride on: drawers carry what stands in them, objects carry what is in or on them.

Small objects are static bodies (no mass, no forces), so nothing carries them by physics: when a
drawer moves, by `World.set_part_state` or pulled by the arm, everything riding on it is moved by
the drawer's displacement, exactly and without settling. Each object has at most one carrier: a
drawer (it stands in one of the drawer's slots) or another object (it is inside, on or under it);
an object rides a drawer when its chain of carriers ends there. A rider and its drawer do not
collide (a static object would otherwise hold the drawer back), which is also why a drawer full of
things slides freely.

The carriers change when the robot picks an object (it rides the hand until put down; what it
carried stays behind, carried by whatever carried it) and puts it down (on whatever is under it).
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
import pybullet as p

from worlds.scene import BuiltScene

Drawer = tuple[int, str]  # (furniture id, part name)
Carrier = Drawer | int  # a drawer, or the instance id of an object


class Riders:
    """The carriers of one built scene's small objects, and the drawer positions last seen.

    Args:
        client: the PyBullet client.
        built: the built scene.
        parents: each object's parent instance id.
    """

    def __init__(self, client: int, built: BuiltScene, parents: Mapping[int, int | None]) -> None:
        """``parents``: each object's parent instance id (a piece of furniture, an object, or None)."""
        self.client, self.built = client, built
        self._carrier: dict[int, Carrier] = {}
        for furniture_id, piece in built.storage.items():
            model = piece.placement.model
            for item_id, slot in piece.placement.contents:
                part = model.slot(slot).part
                if part is not None and model.part(part).kind == "drawer":
                    self._carrier[item_id] = (furniture_id, part)
        for item_id, parent in parents.items():
            if item_id not in self._carrier and parent in built.items:
                self._carrier[item_id] = parent
        self._seen = {drawer: self._joint(drawer) for drawer in self._drawers()}
        for item_id in self._carrier:
            self._collide(item_id, self.drawer_of(item_id), False)

    def _drawers(self) -> list[Drawer]:
        return [
            (furniture_id, part.name)
            for furniture_id, piece in self.built.storage.items()
            for part in piece.placement.model.parts
            if part.kind == "drawer"
        ]

    def _joint(self, drawer: Drawer) -> float:
        piece = self.built.storage[drawer[0]]
        return float(p.getJointState(piece.body, piece.links[drawer[1]], physicsClientId=self.client)[0])

    def drawer_of(self, item_id: int) -> Drawer | None:
        """The drawer ``item_id`` rides on, through its chain of carriers, if any.

        Args:
            item_id: the object's id.

        Returns:
            The drawer, or None.
        """
        carrier = self._carrier.get(item_id)
        seen = {item_id}
        while isinstance(carrier, int) and carrier not in seen:
            seen.add(carrier)
            carrier = self._carrier.get(carrier)
        return carrier if isinstance(carrier, tuple) else None

    def riders(self, drawer: Drawer) -> set[int]:
        """Every object riding on ``drawer``, directly or through other objects.

        Args:
            drawer: the drawer.

        Returns:
            The objects' ids.
        """
        return {item_id for item_id in self._carrier if self.drawer_of(item_id) == drawer}

    def sync(self) -> None:
        """Move the riders of every drawer that moved since the last look by its displacement."""
        for drawer, before in self._seen.items():
            now = self._joint(drawer)
            if now != before:
                self._shift(drawer, now - before)
                self._seen[drawer] = now

    def _shift(self, drawer: Drawer, delta: float) -> None:
        yaw = self.built.storage[drawer[0]].placement.pose[3]
        shift = delta * np.array([math.sin(yaw), -math.cos(yaw), 0.0])  # local -y in the world
        for item_id in self.riders(drawer):
            body = self.built.items[item_id]
            position, orientation = p.getBasePositionAndOrientation(body, physicsClientId=self.client)
            p.resetBasePositionAndOrientation(body, (np.asarray(position) + shift).tolist(), orientation,
                                              physicsClientId=self.client)

    def lift(self, item_id: int) -> None:
        """``item_id`` leaves its carrier (the robot picked it); what it carried stays, on its old carrier.

        Args:
            item_id: the object's id.
        """
        self._collide(item_id, self.drawer_of(item_id), True)
        old = self._carrier.pop(item_id, None)
        for other, carrier in list(self._carrier.items()):
            if carrier == item_id:
                if old is None:
                    del self._carrier[other]
                else:
                    self._carrier[other] = old

    def put(self, item_id: int, support: tuple[int, int] | None) -> None:
        """``item_id`` now stands on ``support`` (body, link): a drawer's link, an object, or anything else.

        Args:
            item_id: the object's id.
            support: what it stands on (body, link), or None.
        """
        carrier: Carrier | None = None
        if support is not None:
            body, link = support
            objects = {b: i for i, b in self.built.items.items()}
            if body in objects and objects[body] != item_id:
                carrier = objects[body]
            for furniture_id, piece in self.built.storage.items():
                names = {index: name for name, index in piece.links.items()}
                if piece.body == body and link in names:
                    name = names[link]
                    parts = {part.name: part for part in piece.placement.model.parts}
                    if name in parts and parts[name].kind == "drawer":
                        carrier = (furniture_id, name)
        if carrier is not None:
            self._carrier[item_id] = carrier
            self._collide(item_id, self.drawer_of(item_id), False)

    def _collide(self, item_id: int, drawer: Drawer | None, enabled: bool) -> None:
        if drawer is None:
            return
        piece = self.built.storage[drawer[0]]
        p.setCollisionFilterPair(self.built.items[item_id], piece.body, -1, piece.links[drawer[1]], int(enabled),
                                 physicsClientId=self.client)
