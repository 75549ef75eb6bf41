"""Which instances of a home a scenario's question is about: its target, as segmentation ids.

An evaluator asks "when did the robot first have the target in view?", so the slots a question
names (`Scenario.target`) must become the instance ids the camera's segmentation shows. The rule,
by the slots named:

- a ``container`` (hidden evidence, "What is inside the fridge in the kitchen?", and door state):
  that storage piece in that room, with its doors, drawers and handles;
- an ``appliance`` (power state): that appliance in that room;
- otherwise every object or piece of furniture matching all of ``category``, ``colour`` and
  ``room`` that are named (identification, location, counting, and existence answered yes);
- nothing matches (an existence question answered no: there is no such thing): the named room,
  seen through its floor.

Storage furniture always brings its parts and handles along: they carry ids of their own, and a
door in view is the piece in view.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from worlds.home import HomeSpec
from worlds.storage_placement import home_storage
from worlds.things import Furniture, Item, Room

#: The slots matched against objects and furniture when no container or appliance is named.
THING_SLOTS = ("category", "colour", "room")


@dataclass(frozen=True)
class Target:
    """What a question is about: its ``kind`` (object, storage, appliance or room), the things
    themselves (labels with their centre ``xy``) and every segmentation id that shows them."""

    kind: str
    things: tuple[dict[str, Any], ...]
    ids: frozenset[int]

    def to_dict(self) -> dict[str, Any]:
        """The target as the episode report carries it.

        Returns:
            Its kind, things and ids.
        """
        return {"kind": self.kind, "things": [dict(thing) for thing in self.things], "ids": sorted(self.ids)}


def question_target(home: HomeSpec, slots: Mapping[str, str | None]) -> Target:
    """The target the slots of `Scenario.target` name in ``home`` (see the module's rule).

    Raises ValueError naming the slots when they name nothing in this home, e.g. a scenario sent
    with another home than the one it was drawn for.

    Args:
        home: the home.
        slots: the scenario's target slots.

    Returns:
        The target.

    Raises:
        ValueError: the slots name nothing in this home.
    """
    room = slots.get("room")
    if slots.get("container"):
        return _furniture_target(home, "storage", slots["container"], room)
    if slots.get("appliance"):
        return _furniture_target(home, "appliance", slots["appliance"], room)
    named = {slot: slots[slot] for slot in THING_SLOTS if slots.get(slot)}
    things = [t for t in (*home.objects, *home.furniture) if all(getattr(t, s) == v for s, v in named.items())]
    if set(named) - {"room"} and things:  # a room alone names a room, not everything in it
        return _target("object", things, home)
    floor = next((r for r in home.rooms if r.name == room), None)
    if floor is None:
        raise ValueError(f"scenario.target: {dict(slots)} names nothing in home {home.seed}")
    return _target("room", [floor], home)


def _furniture_target(home: HomeSpec, kind: str, category: str, room: str | None) -> Target:
    pieces = [f for f in home.furniture if f.category == category and room in (None, f.room)]
    if not pieces:
        raise ValueError(f"scenario.target: no {category} in the {room} of home {home.seed}")
    return _target(kind, pieces, home)


def _target(kind: str, things: list[Item | Furniture | Room], home: HomeSpec) -> Target:
    parts = {placement.furniture_id: set(placement.part_ids().values()) for placement in home_storage(home)}
    ids: set[int] = set()
    for thing in things:
        ids |= {thing.instance_id, *parts.get(thing.instance_id, ())}
    return Target(kind, tuple(_described(thing) for thing in things), frozenset(ids))


def _described(thing: Item | Furniture | Room) -> dict[str, Any]:
    """Id, category, colour, room and the centre ``xy`` in the plane: enough to name and mark it."""
    if isinstance(thing, Room):
        x0, y0, x1, y1 = thing.rect
        return {"id": thing.instance_id, "category": "floor", "colour": thing.floor_colour, "room": thing.name,
                "xy": [round((x0 + x1) / 2, 3), round((y0 + y1) / 2, 3)]}
    return {"id": thing.instance_id, "category": thing.category, "colour": thing.colour, "room": thing.room,
            "xy": [round(float(thing.center[0]), 3), round(float(thing.center[1]), 3)]}
