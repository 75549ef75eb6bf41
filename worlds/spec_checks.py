"""The checks of a scene spec that no single field shows: ids, overlaps, containment, relations.

worlds.spec reads every field on its own first; these checks then look at the home as a whole:
every instance id used once, rooms apart, doorways on the edges of the rooms they join, walls
within the outline, furniture and objects inside their rooms, and every object's parent existing
and able to hold it the way its relation says (a slot of storage for 'inside' furniture, a
container, a cover). Each problem goes to ``fail(path, problem)``. Every check takes time in
proportion to the things checked (rooms: to their square, and they are few).
"""

from __future__ import annotations

from collections.abc import Callable

from worlds.home import HomeSpec
from worlds.things import Furniture, Item, Room, rects_overlap
from worlds.vocabulary import CONTAINERS, COVERS

Fail = Callable[[str, str], None]
_EPS = 1e-6
#: How far a wall may reach beyond the outline of the rooms (its thickness, with room to spare).
WALL_MARGIN_M = 1.0


def check_home(home: HomeSpec, fail: Fail) -> None:
    """What no single field shows: ids, overlaps, containment, and who stands in, on or under what.

    Args:
        home: the home read from a spec.
        fail: called with (path, problem) for each problem.
    """
    owners: dict[int, str] = {}
    for section, things in (("rooms", home.rooms), ("walls", home.walls), ("furniture", home.furniture),
                            ("objects", home.objects)):
        for i, thing in enumerate(things):
            if thing.instance_id in owners:
                fail(f"{section}[{i}].id", f"{thing.instance_id} is already the id of {owners[thing.instance_id]}")
            owners.setdefault(thing.instance_id, f"{section}[{i}]")
    rooms = {}
    for i, room in enumerate(home.rooms):
        if room.name in rooms:
            fail(f"rooms[{i}].name", f"{room.name!r} is used twice")
        for j, other in enumerate(home.rooms[:i]):
            if rects_overlap(room.rect, other.rect):
                fail(f"rooms[{i}].rect", f"overlaps rooms[{j}] ({other.name!r})")
        rooms[room.name] = room
    x0, y0, x1, y1 = home.bounds
    for i, wall in enumerate(home.walls):
        wx0, wy0, wx1, wy1 = wall.footprint
        if wx0 < x0 - WALL_MARGIN_M or wy0 < y0 - WALL_MARGIN_M or wx1 > x1 + WALL_MARGIN_M or wy1 > y1 + WALL_MARGIN_M:
            fail(f"walls[{i}].center", f"the wall reaches beyond the rooms' outline [{x0:g}, {y0:g}, {x1:g}, {y1:g}] "
                                       f"by more than {WALL_MARGIN_M:g} m")
    for i, door in enumerate(home.doorways):
        for name in door.rooms:
            if name not in rooms:
                fail(f"doorways[{i}].rooms", f"{name!r} is not a room")
            elif not _on_edge(rooms[name].rect, *door.center):
                fail(f"doorways[{i}].center", f"{list(door.center)} is not on the edge of {name!r}")
        if door.rooms[0] == door.rooms[1]:
            fail(f"doorways[{i}].rooms", "a doorway joins two different rooms")
    for i, piece in enumerate(home.furniture):
        if piece.room not in rooms:
            fail(f"furniture[{i}].room", f"{piece.room!r} is not a room")
        elif not all(_within(rooms[piece.room].rect, x, y) for x, y in _corners(piece.footprint)):
            fail(f"furniture[{i}].center", f"the piece sticks out of its room {piece.room!r}")
    _check_objects(home, rooms, fail)


def _corners(rect: tuple[float, ...]) -> list[tuple[float, float]]:
    return [(rect[0], rect[1]), (rect[2], rect[1]), (rect[2], rect[3]), (rect[0], rect[3])]


def _within(rect: tuple[float, ...], x: float, y: float) -> bool:
    return rect[0] - _EPS <= x <= rect[2] + _EPS and rect[1] - _EPS <= y <= rect[3] + _EPS


def _on_edge(rect: tuple[float, ...], x: float, y: float) -> bool:
    return _within(rect, x, y) and min(abs(x - rect[0]), abs(x - rect[2]), abs(y - rect[1]), abs(y - rect[3])) < _EPS


def _check_objects(home: HomeSpec, rooms: dict[str, Room], fail: Fail) -> None:
    pieces = {f.instance_id: f for f in home.furniture}
    items = {o.instance_id: o for o in home.objects}
    others = {t.instance_id: kind for kind, things in (("room", home.rooms), ("wall", home.walls)) for t in things}
    for i, item in enumerate(home.objects):
        path = f"objects[{i}]"
        if item.room not in rooms:
            fail(f"{path}.room", f"{item.room!r} is not a room")
        elif not _within(rooms[item.room].rect, item.center[0], item.center[1]):
            fail(f"{path}.center", f"({item.center[0]:g}, {item.center[1]:g}) is outside its room {item.room!r}")
        if item.relation == "floor":
            if item.parent is not None or item.slot is not None:
                fail(f"{path}.parent", "an object on the floor has no parent and no slot (null)")
            continue
        parent = pieces.get(item.parent) or items.get(item.parent)
        if parent is None:
            what = f"a {others[item.parent]}" if item.parent in others else "not an instance id"
            fail(f"{path}.parent", f"{item.parent} is {what}" if item.parent is not None else "missing for relation "
                        f"{item.relation!r}")
            continue
        problem = _relation_problem(item, parent)
        if problem:
            fail(f"{path}.{problem[0]}", problem[1])
        elif parent.room != item.room:
            fail(f"{path}.room", f"{item.room!r} is not the room of its parent ({parent.room!r})")
    settled: set[int] = set()  # objects whose chain of parents ends at furniture or nothing
    for i, item in enumerate(home.objects):
        chain, current = {item.instance_id}, item
        while current.parent in items and current.parent not in settled:
            current = items[current.parent]
            if current.instance_id in chain:
                fail(f"objects[{i}].parent", "objects contain each other in a cycle")
                break
            chain.add(current.instance_id)
        settled |= chain


def _relation_problem(item: Item, parent: Furniture | Item) -> tuple[str, str] | None:
    """(field, problem) when ``item`` cannot stand in its relation to ``parent``; None when it can."""
    if isinstance(parent, Furniture):
        if item.relation == "on":
            return ("slot", "an object on a furniture top has no slot (null)") if item.slot is not None else None
        if item.relation != "inside":
            return ("relation", f"{item.relation!r} needs an object as parent, {item.parent} is furniture")
        if parent.storage is None:
            return ("parent", f"{item.parent} is a {parent.category}, which has no inside")
        if item.slot not in {s.name for s in parent.storage.slots}:
            return ("slot", f"{item.slot!r} is not a slot of {parent.category} {item.parent}")
        return None
    if item.slot is not None:
        return ("slot", "an object in or under another object has no slot (null)")
    if item.relation == "inside" and parent.category not in CONTAINERS:
        return ("parent", f"{item.parent} is a {parent.category}, which holds nothing inside")
    if item.relation == "under" and parent.category not in COVERS:
        return ("parent", f"{item.parent} is a {parent.category}, which covers nothing")
    if item.relation == "on":
        return ("relation", f"'on' needs furniture as parent, {item.parent} is an object")
    return None
