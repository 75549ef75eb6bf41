"""The scene spec: a whole home as one versioned JSON document, written and read back checked.

``dump_spec(home)`` gives a JSON-able dict, ``load_spec(data)`` the `HomeSpec` again (equal to the
one dumped), and ``read_spec_file(path)`` reads a file. Reading checks everything a hand-edited or
foreign file could get wrong (unknown or missing keys, wrong types, non-finite numbers, unknown
words, duplicate ids, overlapping rooms, furniture or objects outside their room, parents that do
not exist or cannot hold the object, joint states beyond their limits) and raises `SpecError` with
one ``path: problem`` line per problem, e.g. ``objects[7].parent: 99 is not an instance id``.
The format is documented in worlds/README.md ("The scene spec").
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

from worlds.fronts import world_size
from worlds.home import HomeSpec
from worlds.spec_checks import check_home
from worlds.spec_fields import FieldChecker, SpecError, shown
from worlds.storage import MODELS, PART_KINDS, Box, Part, Slot, StorageModel
from worlds.things import RELATIONS, Doorway, Furniture, Item, Room, Wall
from worlds.vocabulary import COLOURS, FURNITURE, OBJECTS, ROOM_TYPES, STORAGE_CATEGORIES, room_kind, room_names

__all__ = ["FORMAT", "VERSION", "SpecError", "dump_spec", "load_spec", "read_spec_file"]

FORMAT = "homebot-scene"
VERSION = 2
#: The switches furniture and objects may have, and their positions.
STATES = {"power": ("on", "off"), "curtain": ("open", "closed")}
_JOINTS = {"door": "revolute", "flap": "revolute", "drawer": "prismatic"}
#: Angles and lengths closer than this are equal (a facing of pi/2, a size turned with it).
_EPS = 1e-6
_HINGES = {"door": ("left", "right"), "flap": ("bottom",), "drawer": (None,)}
_TOP = ("format", "version", "seed", "rooms", "walls", "doorways", "furniture", "objects")
#: Bounds of a scene's numbers (metres, radians), far beyond any home: positions, extents of walls,
#: pieces and boxes, doorway widths, facings, joint limits and states, and free-form attributes.
MAX_POSITION_M = 1000.0
MAX_SIZE_M = 100.0
MAX_DOORWAY_M = 10.0
MAX_FACING = 2 * math.pi
MAX_JOINT = 10.0
MAX_ATTRIBUTE = 1e6
#: Instance ids travel in int32 segmentation images; seeds are 64-bit.
MAX_ID = 2**31 - 1
MAX_SEED = 2**63 - 1
#: The largest outline (the rectangle around the rooms) a scene may span: with the counts below, what
#: keeps building a home, drawing its scenario and rasterising its free space to about a second.
MAX_OUTLINE_M2 = 2000.0
MAX_ITEMS = {"rooms": 64, "walls": 1024, "doorways": 256, "furniture": 1024, "objects": 4096}
#: The most parts, slots or panels one storage piece may have.
MAX_PARTS = 64


def _box(box: Box) -> dict[str, Any]:
    return {"name": box.name, "center": list(box.center), "size": list(box.size)}


def _storage(piece: Furniture) -> dict[str, Any] | None:
    model = piece.storage
    if model is None:
        return None
    parts = [{"name": p.name, "kind": p.kind, "joint": p.joint, "lower": p.lower, "upper": p.upper, "hinge": p.hinge,
              "handle": p.handle, "front": list(p.front), "tray": None if p.tray is None else _box(p.tray),
              "state": piece.joints.get(p.name, 0.0)} for p in model.parts]
    slots = [{"name": s.name, "part": s.part, "access": s.access, "center": list(s.center), "size": list(s.size)}
             for s in model.slots]
    return {"model": model.model, "size": list(model.size), "parts": parts, "slots": slots,
            "panels": [_box(b) for b in model.panels]}


def dump_spec(home: HomeSpec) -> dict[str, Any]:
    """``home`` as a JSON-able scene spec (format `FORMAT`, version `VERSION`).

    Args:
        home: the home.

    Returns:
        The spec.
    """
    return {
        "format": FORMAT,
        "version": VERSION,
        "seed": home.seed,
        "rooms": [{"id": r.instance_id, "name": r.name, "type": r.kind, "rect": list(r.rect),
                   "floor_colour": r.floor_colour} for r in home.rooms],
        "walls": [{"id": w.instance_id, "center": list(w.center), "size": list(w.size)} for w in home.walls],
        "doorways": [{"rooms": list(d.rooms), "center": list(d.center), "width": d.width, "along": d.along}
                     for d in home.doorways],
        "furniture": [{"id": f.instance_id, "category": f.category, "colour": f.colour, "room": f.room,
                       "center": list(f.center), "size": list(f.size), "facing": f.facing,
                       "storage": _storage(f), "state": dict(f.state)} for f in home.furniture],
        "objects": [{"id": o.instance_id, "category": o.category, "colour": o.colour, "room": o.room,
                     "center": list(o.center), "relation": o.relation, "parent": o.parent, "slot": o.slot,
                     "attributes": dict(o.attributes), "state": dict(o.state)} for o in home.objects],
    }


def read_spec_file(path: str | Path) -> HomeSpec:
    """The home in the scene spec file ``path``; unreadable JSON is a `SpecError` naming the file.

    Args:
        path: the file.

    Returns:
        The home.

    Raises:
        SpecError: the file is unreadable, not JSON, or not a valid spec.
    """
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"), parse_int=_integer)
    except OSError as error:
        raise SpecError([f"{path}: cannot read ({error.strerror or error})"]) from error
    except (json.JSONDecodeError, UnicodeDecodeError) as error:
        raise SpecError([f"{path}: not valid JSON ({error})"]) from error
    except RecursionError:
        raise SpecError([f"{path}: nested too deeply for a scene spec (a spec nests a few levels)"]) from None
    return load_spec(data)


def _integer(text: str) -> int | float:
    """A JSON integer; one outside the 64-bit range as a float (inf past the float range), which no
    field of a spec takes, so its field's check names it instead of the parser or arithmetic failing."""
    if len(text.lstrip("-")) <= 20:
        value = int(text)
        if -(2**63) <= value < 2**64:
            return value
    return float(text)


def load_spec(data: Any) -> HomeSpec:
    """The home a scene spec describes, after checking every field; `SpecError` lists the problems.

    Args:
        data: the spec.

    Returns:
        The home.

    Raises:
        SpecError: listing every problem.
    """
    reader = _Reader()
    home = reader.home(data)
    if reader.errors or home is None:
        raise SpecError(reader.errors or ["spec: unreadable"])
    return home


class _Reader(FieldChecker):
    """Builds a `HomeSpec` section by section, recording problems instead of stopping at the first."""

    def home(self, data: Any) -> HomeSpec | None:
        top = self.record(data, "", _TOP)
        if top is None:
            return None
        if top["format"] != FORMAT:
            self.fail("format", f"{shown(top['format'])} is not {FORMAT!r}")
        version = self.integer(top["version"], "version", 0, MAX_ID)
        if version is not None and version != VERSION:
            self.fail("version", f"{version} is not supported (expected {VERSION})")
        if self.errors:
            return None
        seed = self.integer(top["seed"], "seed", 0, MAX_SEED)
        sections = {key: self.array(top[key], key) for key in _TOP[3:]}
        for key, items in sections.items():
            if items is not None and len(items) > MAX_ITEMS[key]:
                self.fail(key, f"{len(items)} items, more than the {MAX_ITEMS[key]} a scene may have")
        if self.errors or any(v is None for v in sections.values()):
            return None
        rooms = [self.room(v, f"rooms[{i}]") for i, v in enumerate(sections["rooms"])]
        walls = [self.wall(v, f"walls[{i}]") for i, v in enumerate(sections["walls"])]
        doorways = [self.doorway(v, f"doorways[{i}]") for i, v in enumerate(sections["doorways"])]
        furniture = [self.furniture(v, f"furniture[{i}]") for i, v in enumerate(sections["furniture"])]
        objects = [self.item(v, f"objects[{i}]") for i, v in enumerate(sections["objects"])]
        if not rooms:
            self.fail("rooms", "a home needs at least one room")
        if self.errors or seed is None:
            return None
        self.outline(rooms)
        if self.errors:
            return None
        home = HomeSpec(seed, tuple(rooms), tuple(doorways), tuple(walls), tuple(furniture), tuple(objects))
        check_home(home, self.fail)
        return home

    def outline(self, rooms: list[Room]) -> None:
        """Refuse rooms spread over more than `MAX_OUTLINE_M2` (what the world rasterises)."""
        x0, y0 = min(r.rect[0] for r in rooms), min(r.rect[1] for r in rooms)
        x1, y1 = max(r.rect[2] for r in rooms), max(r.rect[3] for r in rooms)
        if (x1 - x0) * (y1 - y0) > MAX_OUTLINE_M2:
            self.fail("rooms", f"their outline [{x0:g}, {y0:g}, {x1:g}, {y1:g}] spans {(x1 - x0) * (y1 - y0):.0f} m², "
                               f"more than the {MAX_OUTLINE_M2:g} m² a home may")

    def room(self, value: Any, path: str) -> Room | None:
        r = self.record(value, path, ("id", "name", "type", "rect", "floor_colour"))
        if r is None:
            return None
        fields = (self.integer(r["id"], f"{path}.id", 1, MAX_ID), self.word(r["name"], f"{path}.name", room_names()),
                  self.word(r["type"], f"{path}.type", ROOM_TYPES),
                  self.vector(r["rect"], f"{path}.rect", 4, MAX_POSITION_M),
                  self.word(r["floor_colour"], f"{path}.floor_colour", COLOURS))
        if any(f is None for f in fields):
            return None
        room = Room(*fields)
        if room_kind(room.name) != room.kind:
            self.fail(f"{path}.name", f"{room.name!r} is not a name for a room of type {room.kind!r}")
        x0, y0, x1, y1 = room.rect
        if not (x0 < x1 and y0 < y1):
            self.fail(f"{path}.rect", f"{list(room.rect)} must be [xmin, ymin, xmax, ymax] with min < max")
        return room

    def wall(self, value: Any, path: str) -> Wall | None:
        r = self.record(value, path, ("id", "center", "size"))
        if r is None:
            return None
        fields = (self.integer(r["id"], f"{path}.id", 1, MAX_ID),
                  self.vector(r["center"], f"{path}.center", 3, MAX_POSITION_M),
                  self.vector(r["size"], f"{path}.size", 3, MAX_SIZE_M, True))
        return None if any(f is None for f in fields) else Wall(*fields)

    def doorway(self, value: Any, path: str) -> Doorway | None:
        r = self.record(value, path, ("rooms", "center", "width", "along"))
        if r is None:
            return None
        names = self.array(r["rooms"], f"{path}.rooms")
        if names is not None and (len(names) != 2 or not all(isinstance(n, str) for n in names)):
            self.fail(f"{path}.rooms", "expected the names of the two rooms it joins")
            names = None
        fields = (self.vector(r["center"], f"{path}.center", 2, MAX_POSITION_M),
                  self.number(r["width"], f"{path}.width", MAX_DOORWAY_M, True),
                  self.word(r["along"], f"{path}.along", ("x", "y")))
        if names is None or any(f is None for f in fields):
            return None
        return Doorway((names[0], names[1]), *fields)

    def furniture(self, value: Any, path: str) -> Furniture | None:
        keys = ("id", "category", "colour", "room", "center", "size", "facing", "storage", "state")
        r = self.record(value, path, keys)
        if r is None:
            return None
        fields = (self.integer(r["id"], f"{path}.id", 1, MAX_ID),
                  self.word(r["category"], f"{path}.category", FURNITURE),
                  self.word(r["colour"], f"{path}.colour", COLOURS), self.word(r["room"], f"{path}.room"),
                  self.vector(r["center"], f"{path}.center", 3, MAX_POSITION_M),
                  self.vector(r["size"], f"{path}.size", 3, MAX_SIZE_M, True),
                  self.number(r["facing"], f"{path}.facing", MAX_FACING))
        state = self.words(r["state"], f"{path}.state", STATES)
        storage = None if r["storage"] is None else self.storage(r["storage"], f"{path}.storage")
        if any(f is None for f in fields) or state is None or (r["storage"] is not None and storage is None):
            return None
        category, facing = fields[1], fields[6]
        if abs(math.remainder(facing, math.pi / 2)) > _EPS:
            self.fail(f"{path}.facing", f"{facing} is not a multiple of pi/2 (pieces stand square to the walls)")
            return None
        model, joints = storage if storage is not None else (None, {})
        if (category in STORAGE_CATEGORIES) != (model is not None):
            need = "needs a storage model" if model is None else "has no storage (storage must be null)"
            self.fail(f"{path}.storage", f"a {category} {need}")
        elif model is not None:
            if model.model != category.replace(" ", "_"):
                self.fail(f"{path}.storage.model", f"{model.model!r} does not match category {category!r}")
            turned = world_size(model.size, facing)
            if any(abs(a - b) > _EPS for a, b in zip(turned, fields[5])):
                self.fail(f"{path}.size", f"{list(fields[5])} is not storage.size turned to face {facing:g}")
        return Furniture(*fields, model, joints, state)

    def storage(self, value: Any, path: str) -> tuple[StorageModel, dict[str, float]] | None:
        r = self.record(value, path, ("model", "size", "parts", "slots", "panels"))
        if r is None:
            return None
        name = self.word(r["model"], f"{path}.model", MODELS)
        size = self.vector(r["size"], f"{path}.size", 3, MAX_SIZE_M, True)
        lists = [self.array(r[k], f"{path}.{k}") for k in ("parts", "slots", "panels")]
        for key, items in zip(("parts", "slots", "panels"), lists):
            if items is not None and not (key != "panels" or items):
                self.fail(f"{path}.panels", "a piece needs at least one panel")
            elif items is not None and len(items) > MAX_PARTS:
                self.fail(f"{path}.{key}", f"{len(items)} items, more than the {MAX_PARTS} a piece may have")
        if name is None or size is None or any(v is None or len(v) > MAX_PARTS for v in lists) or not lists[2]:
            return None
        read = [self.part(v, f"{path}.parts[{i}]") for i, v in enumerate(lists[0])]
        slots = [self.slot(v, f"{path}.slots[{i}]") for i, v in enumerate(lists[1])]
        panels = [self.box(v, f"{path}.panels[{i}]") for i, v in enumerate(lists[2])]
        if any(v is None for v in (*read, *slots, *panels)):
            return None
        parts = [part for part, _ in read]
        links = {"carcass"}  # each part, each handle and the carcass is a link of the piece's model
        for i, part in enumerate(parts):
            for key, link in (("name", part.name), ("handle", part.handle)):
                if link in links:
                    self.fail(f"{path}.parts[{i}].{key}", f"{link!r} is used twice (or is the carcass's name)")
                links.add(link)
        kinds = {p.name: p.kind for p in parts}
        for i, slot in enumerate(slots):
            if slot.part is not None and kinds.get(slot.part) != "drawer":
                self.fail(f"{path}.slots[{i}].part", f"{slot.part!r} is not a drawer of this piece")
            if slot.access not in kinds:
                self.fail(f"{path}.slots[{i}].access", f"{slot.access!r} is not a part of this piece")
        model = StorageModel(name, size, tuple(parts), tuple(slots), tuple(panels))
        return model, {part.name: state for part, state in read}

    def part(self, value: Any, path: str) -> tuple[Part, float] | None:
        keys = ("name", "kind", "joint", "lower", "upper", "hinge", "handle", "front", "tray", "state")
        r = self.record(value, path, keys)
        if r is None:
            return None
        kind = self.word(r["kind"], f"{path}.kind", PART_KINDS)
        joints = set(_JOINTS.values())
        fields = (self.name(r["name"], f"{path}.name"), kind, self.word(r["joint"], f"{path}.joint", joints),
                  self.number(r["lower"], f"{path}.lower", MAX_JOINT),
                  self.number(r["upper"], f"{path}.upper", MAX_JOINT))
        handle = self.name(r["handle"], f"{path}.handle")
        front = self.vector(r["front"], f"{path}.front", 4, MAX_SIZE_M)
        tray = None if r["tray"] is None else self.box(r["tray"], f"{path}.tray")
        state = self.number(r["state"], f"{path}.state", MAX_JOINT)
        if any(f is None for f in (*fields, handle, front, state)) or (r["tray"] is not None and tray is None):
            return None
        name, kind, joint, lower, upper = fields
        if joint != _JOINTS[kind]:
            self.fail(f"{path}.joint", f"a {kind} moves on a {_JOINTS[kind]} joint, not {joint}")
        if r["hinge"] not in _HINGES[kind]:
            self.fail(f"{path}.hinge", f"{shown(r['hinge'])} is not a hinge of a {kind} ({_HINGES[kind]})")
        if (tray is None) != (kind != "drawer"):
            self.fail(f"{path}.tray", "a drawer has a tray, doors and flaps have none (null)")
        if lower > upper:
            self.fail(f"{path}.upper", f"{upper} is below the lower limit {lower}")
        elif state < lower:
            self.fail(f"{path}.state", f"{state} is below the joint's lower limit {lower}")
        elif state > upper:
            self.fail(f"{path}.state", f"{state} is above the joint's upper limit {upper}")
        return Part(name, kind, joint, lower, upper, r["hinge"], handle, front, tray), state

    def slot(self, value: Any, path: str) -> Slot | None:
        r = self.record(value, path, ("name", "part", "access", "center", "size"))
        if r is None:
            return None
        fields = (self.name(r["name"], f"{path}.name"), self.name(r["access"], f"{path}.access"),
                  self.vector(r["center"], f"{path}.center", 3, MAX_POSITION_M),
                  self.vector(r["size"], f"{path}.size", 3, MAX_SIZE_M, True))
        part = None if r["part"] is None else self.name(r["part"], f"{path}.part")
        if any(f is None for f in fields) or (r["part"] is not None and part is None):
            return None
        name, access, center, size = fields
        return Slot(name, part, access, center, size)

    def box(self, value: Any, path: str) -> Box | None:
        r = self.record(value, path, ("name", "center", "size"))
        if r is None:
            return None
        fields = (self.name(r["name"], f"{path}.name"), self.vector(r["center"], f"{path}.center", 3, MAX_POSITION_M),
                  self.vector(r["size"], f"{path}.size", 3, MAX_SIZE_M, True))
        return None if any(f is None for f in fields) else Box(*fields)

    def item(self, value: Any, path: str) -> Item | None:
        keys = ("id", "category", "colour", "room", "center", "relation", "parent", "slot", "attributes", "state")
        r = self.record(value, path, keys)
        if r is None:
            return None
        fields = (self.integer(r["id"], f"{path}.id", 1, MAX_ID),
                  self.word(r["category"], f"{path}.category", OBJECTS),
                  self.word(r["colour"], f"{path}.colour", COLOURS), self.word(r["room"], f"{path}.room"),
                  self.vector(r["center"], f"{path}.center", 3, MAX_POSITION_M),
                  self.word(r["relation"], f"{path}.relation", RELATIONS))
        parent = None if r["parent"] is None else self.integer(r["parent"], f"{path}.parent", 1, MAX_ID)
        slot = self.optional_word(r["slot"], f"{path}.slot")
        extra = (self.scalars(r["attributes"], f"{path}.attributes", MAX_ATTRIBUTE),
                 self.words(r["state"], f"{path}.state", STATES))
        bad_links = (r["parent"] is not None and parent is None) or (r["slot"] is not None and slot is None)
        if any(f is None for f in (*fields, *extra)) or bad_links:
            return None
        return Item(*fields, parent, slot, *extra)
