"""A symbolic tabletop: things with places and states, skills that change them, a perception
that reports only what can be seen. Perception and skill executor for the explorer, without a
simulator.

Being seen: a thing is visible when every one of its ``hidden_by`` holds: each names a part that
must be open (the door in front of a shelf) or a cover that must be away (the box over a doll).
Acting is checked as a careful robot would find it: a part opens only while nothing that
``blocks`` it stands at its start place, and closes only then too; a thing can be picked only when
visible, put back only when its place can be reached again (its door open, no cover back over
it). So an exploration that does things in the wrong order fails here instead of passing.

`SymbolicScene.from_tabletop` builds one from a `worlds.tabletop_scene.TabletopScene` (read by
its fields, nothing imported): the same instance ids, parents and relations as its ground-truth
ACSG, blockers from the scene's own geometric test. The perception passes that test's answer as
the ``blocks`` hint, as a geometry-aware perception would.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from agent.acsg.interfaces import Detection, SkillCall, SkillResult

_OPEN = {"open_door": "door", "open_drawer": "drawer", "open": None}
_CLOSE = {"close_door": "door", "close_drawer": "drawer", "close": None}


@dataclass
class Thing:
    """One instance: the table, a piece of storage, a part (``part`` = "door" or "drawer"), a
    handle, or a small thing (``pickable``)."""

    instance: str
    label: str
    parent: str | None = None
    relation: str | None = None
    position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    size: tuple[float, float, float] = (0.05, 0.05, 0.05)
    part: str | None = None
    hidden_by: tuple[str, ...] = ()
    blocks: tuple[str, ...] = ()
    pickable: bool = False
    attributes: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.instance = str(self.instance)
        self.parent = None if self.parent is None else str(self.parent)
        self.hidden_by = tuple(str(h) for h in self.hidden_by)
        self.blocks = tuple(str(b) for b in self.blocks)
        if self.part not in (None, "door", "drawer"):
            raise ValueError(f"thing {self.instance}: part {self.part!r} is not 'door', 'drawer' or None")


class SymbolicScene:
    """The scene's state (open parts, things moved to the idle space) and the two interfaces on it.

    Args:
        things: the scene's things, each with its parent, what hides it and what it blocks.
        idle_spot: where things picked away are put.

    Raises:
        ValueError: an instance id used twice, or one naming a thing not in the scene.
    """

    def __init__(self, things: Iterable[Thing], idle_spot: tuple[float, float, float] = (0.0, -2.0, 0.75)) -> None:
        self.things: dict[str, Thing] = {}
        for thing in things:
            if thing.instance in self.things:
                raise ValueError(f"thing {thing.instance}: instance id used twice")
            self.things[thing.instance] = thing
        for thing in self.things.values():
            for name, ids in (("parent", [thing.parent] if thing.parent else []), ("hidden_by", thing.hidden_by),
                              ("blocks", thing.blocks)):
                unknown = [i for i in ids if i not in self.things]
                if unknown:
                    raise ValueError(f"thing {thing.instance}: {name} names unknown instances {unknown}")
        self.open: set[str] = set()
        self.away: dict[str, np.ndarray] = {}
        self.idle_spot = np.asarray(idle_spot, dtype=float)
        self.calls: list[SkillCall] = []

    # ---- state --------------------------------------------------------------------------------
    def visible(self, instance: str) -> bool:
        """Whether nothing hides ``instance`` now (every part or thing hiding it open or moved away).

        Args:
            instance: the thing's instance.

        Returns:
            Whether it is visible.
        """
        return all(self._clear(h) for h in self.things[instance].hidden_by)

    def _clear(self, hider: str) -> bool:
        return hider in self.open if self.things[hider].part else hider in self.away

    def position(self, instance: str) -> np.ndarray:
        """Where ``instance`` is now: where it was moved to, else where it started.

        Args:
            instance: the thing's instance.

        Returns:
            The position.
        """
        return self.away.get(instance, np.asarray(self.things[instance].position, dtype=float))

    def positions(self) -> dict[str, np.ndarray]:
        """Instance -> where it is now, for every pickable thing.

        Returns:
            The positions.
        """
        return {i: self.position(i) for i, t in self.things.items() if t.pickable}

    def start_positions(self) -> dict[str, np.ndarray]:
        """Instance -> where it started, for every pickable thing.

        Returns:
            The positions.
        """
        return {i: np.asarray(t.position, dtype=float) for i, t in self.things.items() if t.pickable}

    def part_states(self) -> dict[str, float]:
        """Part instance -> 1.0 open, 0.0 closed.

        Returns:
            The states.
        """
        return {i: float(i in self.open) for i, t in self.things.items() if t.part}

    def start_part_states(self) -> dict[str, float]:
        """Part instance -> 0.0: every part starts closed.

        Returns:
            The states.
        """
        return {i: 0.0 for i, t in self.things.items() if t.part}

    def _in_the_way(self, part: str) -> list[str]:
        return [i for i, t in self.things.items() if part in t.blocks and i not in self.away]

    # ---- Perception -----------------------------------------------------------------------------
    def observe(self) -> list[Detection]:
        """Everything visible now, as detections (parts with their open state).

        Returns:
            The detections.
        """
        found = []
        for i, thing in self.things.items():
            if not self.visible(i):
                continue
            attributes = dict(thing.attributes)
            if thing.part:
                attributes["state"] = "open" if i in self.open else "closed"
            hints = {"blocks": thing.blocks} if thing.blocks and i not in self.away else {}
            found.append(Detection(i, thing.label, thing.parent, thing.relation, attributes,
                                   self.position(i), np.asarray(thing.size, dtype=float), hints))
        return found

    # ---- SkillExecutor ------------------------------------------------------------------------
    def execute(self, call: SkillCall) -> SkillResult:
        """Run a primitive on the symbolic scene: open, close, pick away, put back or move the camera.

        Args:
            call: the primitive and what it acts on.

        Returns:
            How it went; a failure says why.
        """
        self.calls.append(call)
        instance = call.instance
        if instance not in self.things:
            return SkillResult(False, f"no instance {instance!r} in the scene")
        thing = self.things[instance]
        if call.primitive == "move_camera":
            return SkillResult(True)
        if not self.visible(instance) and not (call.primitive == "pick_back" and instance in self.away):
            return SkillResult(False, f"{thing.label} {instance} cannot be seen")
        if call.primitive in _OPEN or call.primitive in _CLOSE:
            return self._move_part(call.primitive, thing)
        if call.primitive == "pick_away":
            if not thing.pickable:
                return SkillResult(False, f"{thing.label} {instance} cannot be picked")
            if instance in self.away:
                return SkillResult(False, f"{thing.label} {instance} is already away")
            self.away[instance] = self.idle_spot + np.array([0.12 * len(self.away), 0.0, 0.0])
            return SkillResult(True)
        if call.primitive == "pick_back":
            if instance not in self.away:
                return SkillResult(False, f"{thing.label} {instance} is not away")
            shut = [h for h in thing.hidden_by if not self._clear(h)]
            if shut:
                return SkillResult(False, f"{thing.label} {instance}: its place is closed off by {shut}")
            del self.away[instance]
            return SkillResult(True)
        return SkillResult(False, f"unknown primitive {call.primitive!r}")

    def _move_part(self, primitive: str, thing: Thing) -> SkillResult:
        opening = primitive in _OPEN
        kind = _OPEN.get(primitive) if opening else _CLOSE.get(primitive)
        if thing.part is None:
            return SkillResult(False, f"{thing.label} {thing.instance} is not a door or drawer")
        if kind is not None and kind != thing.part:
            return SkillResult(False, f"{thing.label} {thing.instance} is a {thing.part}, not a {kind}")
        if opening == (thing.instance in self.open):
            return SkillResult(False, f"{thing.label} {thing.instance} is already {'open' if opening else 'closed'}")
        blockers = self._in_the_way(thing.instance)
        if blockers:
            names = ", ".join(f"{self.things[b].label} {b}" for b in blockers)
            return SkillResult(False, f"{thing.label} {thing.instance} is blocked by {names}")
        (self.open.add if opening else self.open.discard)(thing.instance)
        return SkillResult(True)

    # ---- from a tabletop scene ----------------------------------------------------------------
    @classmethod
    def from_tabletop(cls, scene: Any) -> SymbolicScene:
        """The symbolic twin of a `TabletopScene`: its ids, parents and relations, hidden places
        (storage slots behind their access part, things under open-bottom boxes) and blockers.

        Args:
            scene: the tabletop scene.

        Returns:
            The symbolic scene.
        """
        labels = scene.labels()
        table = next(i for i, label in labels.items() if label["category"] == "table")

        def colour(i: int) -> dict[str, Any]:
            return {"colour": labels[i]["colour"]}

        things = [Thing(str(table), "table", attributes=colour(table))]
        pieces = {}
        for _, placement in scene.storage:
            piece, ids = placement.furniture_id, placement.part_ids()
            pieces[piece] = placement
            where = tuple(float(v) for v in placement.pose[:3])
            things.append(Thing(str(piece), labels[piece]["category"], str(table), "on", where,
                                tuple(float(v) for v in placement.model.size), attributes=colour(piece)))
            for part in placement.model.parts:
                pid, hid = ids[part.name], ids[part.handle]
                kind = "drawer" if part.kind == "drawer" else "door"
                things.append(Thing(str(pid), labels[pid]["category"], str(piece), "belongs", where, part=kind,
                                    attributes=colour(pid)))
                things.append(Thing(str(hid), labels[hid]["category"], str(pid), "belongs", where,
                                    attributes=colour(hid)))
        objects = {o.instance_id: o for o in scene.objects}

        def place(o: Any) -> tuple[str, tuple[str, ...]]:
            """(parent instance, hidden_by) as the ground truth has them."""
            if o.slot is not None:
                placement = pieces[o.parent]
                slot = placement.model.slot(o.slot)
                ids = placement.part_ids()
                parent = ids[slot.part] if slot.part is not None else o.parent
                return str(parent), (str(ids[slot.access]),)
            if o.relation == "inside" and o.parent in objects:
                return str(o.parent), (*place(objects[o.parent])[1], str(o.parent))
            return str(o.parent), ()

        blocks: dict[int, list[str]] = {}
        for obstacle, piece, part in scene.blockers():
            blocks.setdefault(obstacle, []).append(str(pieces[piece].part_ids()[part]))
        for o in scene.objects:
            parent, hidden_by = place(o)
            things.append(Thing(
                str(o.instance_id), o.category, parent, o.relation, tuple(float(v) for v in o.center),
                tuple(float(v) for v in 2 * np.asarray(o.half_extents)), hidden_by=hidden_by,
                blocks=tuple(blocks.get(o.instance_id, ())), pickable=True,
                attributes={**colour(o.instance_id), "shape": o.shape},
            ))
        return cls(things)
