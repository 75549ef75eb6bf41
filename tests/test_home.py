"""The home generator: deterministic, the size asked for, furnished with storage that can open and be
reached, objects in consistent places, and every room reachable by the robot."""

from __future__ import annotations

import dataclasses
import json
import math
import time
from collections import Counter

import numpy as np
import pytest

from worlds.appearance import DARK_SCREEN, HOT_BURNER, LIT_SCREEN, LIT_SHADE, furniture_visuals, item_visuals
from worlds.freespace import free_space, reachable_rooms
from worlds.fronts import slot_box, stand_point
from worlds.furnish import DOOR_CLEARANCE, STAND, clear_zone
from worlds.home import HomeSpec, generate_home
from worlds.robot import ROBOT_RADIUS, CameraConfig
from worlds.sim import World
from worlds.spec import dump_spec
from worlds.things import Furniture, Item, Wall, rects_overlap
from worlds.vocabulary import (
    APPLIANCES, COLOURS, CONTAINERS, COVERS, FURNITURE, OBJECTS, ROOM_TYPES, STORAGE_CATEGORIES, room_kind, room_names,
)

SEEDS = range(30)
#: (n_rooms, area_m2) asked for; None lets the seed choose.
SIZES = [(4, 60.0), (6, 150.0), (10, 300.0), (7, None), (None, 220.0), (None, None)]


@pytest.fixture(scope="module")
def homes() -> list[HomeSpec]:
    return [generate_home(seed, *SIZES[seed % len(SIZES)]) for seed in SEEDS]


def _depth(item: Item, objects: dict[int, Item]) -> int:
    """How many objects an object sits in or under before reaching furniture or the floor."""
    depth = 0
    while item.parent in objects:
        item, depth = objects[item.parent], depth + 1  # type: ignore[index]
    return depth


def test_same_seed_gives_the_same_home_and_spec_and_different_seeds_differ() -> None:
    assert generate_home(7) == generate_home(7)
    assert json.dumps(dump_spec(generate_home(7, 8, 200.0))) == json.dumps(dump_spec(generate_home(7, 8, 200.0)))
    texts = {json.dumps(dump_spec(generate_home(seed))) for seed in range(8)}
    assert len(texts) == 8


@pytest.mark.parametrize("n_rooms, area", SIZES)
def test_room_count_and_area_are_what_was_asked(n_rooms: int | None, area: float | None) -> None:
    for seed in range(5):
        home = generate_home(seed, n_rooms, area)
        assert len(home.rooms) == n_rooms if n_rooms is not None else 4 <= len(home.rooms) <= 10
        assert home.area_m2 == pytest.approx(area, rel=0.1) if area is not None else 60 * 0.9 <= home.area_m2 <= 300 * 1.1


def test_sizes_are_drawn_from_the_seed_over_the_whole_range() -> None:
    homes = [generate_home(seed) for seed in range(40)]
    counts = Counter(len(h.rooms) for h in homes)
    assert min(counts) <= 5 and max(counts) >= 9
    assert min(h.area_m2 for h in homes) < 120 and max(h.area_m2 for h in homes) > 200


def test_sizes_are_checked() -> None:
    for kwargs, field in (({"n_rooms": 3}, "n_rooms"), ({"n_rooms": 11}, "n_rooms"), ({"area_m2": 40.0}, "area_m2"),
                          ({"area_m2": 400.0}, "area_m2"), ({"area_m2": float("nan")}, "area_m2"),
                          ({"n_rooms": 10, "area_m2": 60.0}, "area_m2")):
        with pytest.raises(ValueError, match=field):
            generate_home(1, **kwargs)


def test_a_big_home_is_made_quickly() -> None:
    started = time.perf_counter()
    for seed in range(3):
        generate_home(seed, 10, 300.0)
    assert (time.perf_counter() - started) / 3 < 1.0


def test_rooms_have_unique_names_of_their_kind_and_ids_run_one_to_n(homes: list[HomeSpec]) -> None:
    kinds = Counter()
    for home in homes:
        names = [room.name for room in home.rooms]
        assert len(set(names)) == len(names)
        for room in home.rooms:
            assert room.kind in ROOM_TYPES and room.name in room_names() and room_kind(room.name) == room.kind
            kinds[room.kind] += 1
        assert {"kitchen", "living room", "bedroom", "bathroom"} <= {room.kind for room in home.rooms}
        ids = sorted(home.labels())
        assert ids == list(range(1, len(ids) + 1))
    assert set(kinds) == set(ROOM_TYPES)
    assert any(room.name == "second bedroom" for home in homes for room in home.rooms)


def test_every_room_is_reachable_for_the_robot_disc(homes: list[HomeSpec]) -> None:
    for home in homes:
        assert reachable_rooms(home, ROBOT_RADIUS) == {room.name for room in home.rooms}, home.seed


def test_closing_a_doorway_cuts_its_room_off() -> None:
    """The reachability check is not vacuous: walling up a dead-end room's only door isolates it."""
    for seed in SEEDS:
        home = generate_home(seed)
        doors = Counter(name for door in home.doorways for name in door.rooms)
        dead_ends = [name for name, count in doors.items() if count == 1]
        if dead_ends:
            break
    else:
        pytest.fail("no home with a dead-end room")
    door = next(d for d in home.doorways if dead_ends[0] in d.rooms)
    size = (door.width, 0.1, 2.5) if door.along == "x" else (0.1, door.width, 2.5)
    closed = dataclasses.replace(home, walls=(*home.walls, Wall(9999, (*door.center, 1.25), size)))
    assert dead_ends[0] not in reachable_rooms(closed, ROBOT_RADIUS)


def test_doorways_are_wide_and_kept_clear(homes: list[HomeSpec]) -> None:
    for home in homes:
        for door in home.doorways:
            assert 0.9 <= door.width <= 1.1
            zone = door.clear_zone(DOOR_CLEARANCE, side_margin=0.0)
            blocking = [f for f in home.furniture if rects_overlap(f.footprint, zone)]
            blocking += [o for o in home.objects if o.relation == "floor" and rects_overlap(o.footprint, zone)]
            assert not blocking, (home.seed, door, blocking)


def test_furniture_suits_its_room_and_stands_apart(homes: list[HomeSpec]) -> None:
    for home in homes:
        rooms = {room.name: room for room in home.rooms}
        for i, piece in enumerate(home.furniture):
            assert rooms[piece.room].kind in FURNITURE[piece.category][1]
            x0, y0, x1, y1 = piece.footprint
            assert rooms[piece.room].contains(x0, y0) and rooms[piece.room].contains(x1, y1)
            assert all(not rects_overlap(piece.footprint, other.footprint) for other in home.furniture[:i])
        essentials = {(f.room, f.category) for f in home.furniture}
        assert all((r.name, "bed") in essentials for r in home.rooms if r.kind == "bedroom"), home.seed


def test_storage_has_a_clear_front_the_robot_can_stand_in(homes: list[HomeSpec]) -> None:
    storage = 0
    for home in homes:
        space = free_space(home, ROBOT_RADIUS)
        main = space.main_component()
        floor_items = [o for o in home.objects if o.relation == "floor"]
        for piece in home.furniture:
            assert (piece.storage is not None) == (piece.category in STORAGE_CATEGORIES)
            if piece.storage is None:
                continue
            storage += 1
            assert piece.storage.model == piece.category.replace(" ", "_")
            zone = clear_zone(piece)
            room = next(r for r in home.rooms if r.name == piece.room)
            assert room.contains(zone[0], zone[1]) and room.contains(zone[2], zone[3])
            assert not [f for f in home.furniture if f is not piece and rects_overlap(zone, f.footprint)], piece
            assert not [o for o in floor_items if rects_overlap(zone, o.footprint)], piece
            row, col = space.cell_at(*stand_point(piece, STAND / 2))
            assert space.components[row, col] == main, (home.seed, piece.category)
    assert storage >= 3 * len(homes)


def test_most_parts_are_closed_and_switches_are_set(homes: list[HomeSpec]) -> None:
    joints = [(piece, name, value) for home in homes for piece in home.furniture for name, value in piece.joints.items()]
    open_parts = [(piece, name, value) for piece, name, value in joints if value > 0]
    assert 0 < len(open_parts) < 0.3 * len(joints)
    for piece, name, value in joints:
        part = piece.storage.part(name)  # type: ignore[union-attr]
        assert part.lower <= value <= part.upper
    states = Counter()
    for piece in (f for home in homes for f in home.furniture):
        if piece.category in APPLIANCES:
            assert piece.state["power"] in ("on", "off")
            states[piece.state["power"]] += 1
        elif piece.category == "curtain":
            assert piece.state["curtain"] in ("open", "closed")
            states[piece.state["curtain"]] += 1
        else:
            assert piece.state == {}
    assert set(states) == {"on", "off", "open", "closed"}


def test_objects_stand_where_their_relation_says(homes: list[HomeSpec]) -> None:
    relations, depths = Counter(), Counter()
    for home in homes:
        rooms = {room.name: room for room in home.rooms}
        pieces: dict[int, Furniture] = {f.instance_id: f for f in home.furniture}
        objects = {o.instance_id: o for o in home.objects}
        covered = {o.parent: o for o in home.objects if o.relation == "under"}
        for item in home.objects:
            assert item.category in OBJECTS and item.colour in COLOURS
            assert rooms[item.room].contains(item.center[0], item.center[1])
            relations[item.relation] += 1
            depths[_depth(item, objects)] += 1
            bottom = item.center[2] - item.half_extents[2]
            if item.category == "towel" and item.instance_id in covered:  # laid over what it hides
                bottom -= 2 * covered[item.instance_id].half_extents[2]
            if item.relation == "floor":
                assert item.parent is None and item.slot is None and bottom == pytest.approx(0.0)
                continue
            parent = pieces.get(item.parent) or objects[item.parent]  # type: ignore[index]
            assert parent.room == item.room
            if item.relation == "on":
                assert isinstance(parent, Furniture) and item.slot is None
                assert bottom == pytest.approx(parent.top_z)
                _assert_within(item.footprint, parent.footprint)
            elif item.relation == "inside" and isinstance(parent, Furniture):
                (cx, cy, cz), (sx, sy, sz) = slot_box(parent, item.slot)  # type: ignore[arg-type]
                assert bottom == pytest.approx(cz - sz / 2) and 2 * item.half_extents[2] <= sz + 1e-9
                _assert_within(item.footprint, (cx - sx / 2, cy - sy / 2, cx + sx / 2, cy + sy / 2))
            elif item.relation == "inside":
                assert parent.category in CONTAINERS and item.slot is None
                _assert_within(item.footprint, parent.footprint)
                assert parent.center[2] - parent.half_extents[2] < bottom < parent.center[2]
            else:
                assert item.relation == "under" and parent.category in COVERS and item.slot is None
                _assert_within(item.footprint, parent.footprint)
                top = item.center[2] + item.half_extents[2]
                if parent.category == "towel":
                    assert top == pytest.approx(parent.center[2] - parent.half_extents[2])
                else:
                    assert parent.attributes == {"upturned": True} and top < parent.center[2] + parent.half_extents[2]
    assert set(relations) == {"on", "inside", "under", "floor"}
    assert max(depths) >= 2, depths


def _assert_within(inner: tuple[float, ...], outer: tuple[float, ...]) -> None:
    eps = 1e-6
    assert outer[0] - eps <= inner[0] and outer[1] - eps <= inner[1] and inner[2] <= outer[2] + eps and inner[3] <= outer[3] + eps


def test_objects_scale_with_floor_area_and_suit_their_rooms(homes: list[HomeSpec]) -> None:
    small = [generate_home(seed, 4, 60.0) for seed in range(5)]
    large = [generate_home(seed, 10, 300.0) for seed in range(5)]
    assert np.mean([len(h.objects) for h in large]) > 3 * np.mean([len(h.objects) for h in small])
    bathroom = Counter(o.category for h in homes for o in h.objects if room_kind(o.room) == "bathroom")
    kitchen = Counter(o.category for h in homes for o in h.objects if room_kind(o.room) == "kitchen")
    assert bathroom["toothbrush"] > kitchen["toothbrush"] and kitchen["cereal box"] > bathroom["cereal box"]


def test_switches_change_how_things_look() -> None:
    pieces = {f.category: f for seed in range(5) for f in generate_home(seed, 10, 300.0).furniture}
    lamp, tv, curtain = pieces["lamp"], pieces["tv"], pieces["curtain"]

    def look(piece: Furniture, **state: str) -> list:
        return [v.rgba for v in furniture_visuals(dataclasses.replace(piece, state=state))]

    assert LIT_SHADE in look(lamp, power="on") and LIT_SHADE not in look(lamp, power="off")
    assert LIT_SCREEN in look(tv, power="on") and LIT_SCREEN not in look(tv, power="off")
    assert DARK_SCREEN in look(tv, power="off")
    stove = Furniture(1, "stove", "white", "kitchen", (1.0, 1.0, 0.45), (0.6, 0.62, 0.9), 0.0, state={"power": "on"})
    assert HOT_BURNER in [v.rgba for v in furniture_visuals(stove)]
    closed = furniture_visuals(dataclasses.replace(curtain, state={"curtain": "closed"}))
    opened = furniture_visuals(dataclasses.replace(curtain, state={"curtain": "open"}))
    cloth = COLOURS[curtain.colour]
    assert sum(max(v.dims[:2]) for v in closed if v.rgba == cloth) > 2 * sum(max(v.dims[:2]) for v in opened if v.rgba == cloth)
    lamp_item = Item(2, "table lamp", "red", "bedroom", (0.0, 0.0, 0.8), "on", 1, None, {}, {"power": "on"})
    assert LIT_SHADE in [v.rgba for v in item_visuals(lamp_item)]
    plain = Furniture(3, "sofa", "grey", "living room", (1.0, 1.0, 0.4), (1.9, 0.85, 0.8))
    assert [(v.shape, v.center, v.dims) for v in furniture_visuals(plain)] == [("box", plain.center, plain.size)]


def test_switches_show_in_the_camera_frame() -> None:
    """Rendered by PyBullet: a TV that is on shows a bright screen, one that is off a black one."""
    home = generate_home(2, 10, 300.0)
    tv = next(f for f in home.furniture if f.category == "tv")
    x, y = stand_point(tv, 1.6)
    looks = {}
    world = World(CameraConfig())
    try:
        for power in ("on", "off"):
            switched = dataclasses.replace(tv, state={"power": power})
            world.build(dataclasses.replace(home, furniture=tuple(switched if f is tv else f for f in home.furniture)))
            world.place((x, y, tv.facing + math.pi))
            frame = world.observe()
            pixels = frame.rgb[frame.seg == tv.instance_id].astype(float)
            assert len(pixels) > 500
            looks[power] = pixels
    finally:
        world.close()
    lit = {power: float((rgb[:, 2] - rgb[:, 0] > 40).mean()) for power, rgb in looks.items()}  # a blue screen
    assert lit["on"] > 0.3 and lit["off"] < 0.05
