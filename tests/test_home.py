"""The home generator: deterministic, well-formed, furnished, and every room reachable by the robot."""

from __future__ import annotations

import dataclasses
import json
from collections import Counter

import pytest

from worlds.freespace import reachable_rooms
from worlds.furnish import DOOR_CLEARANCE
from worlds.home import HomeSpec, generate_home
from worlds.robot import ROBOT_RADIUS
from worlds.things import Wall, rects_overlap
from worlds.vocabulary import COLOURS, FURNITURE, OBJECTS, ROOM_TYPES

SEEDS = range(40)


@pytest.fixture(scope="module")
def homes() -> list[HomeSpec]:
    return [generate_home(seed) for seed in SEEDS]


def test_same_seed_gives_the_same_home_and_different_seeds_differ() -> None:
    assert generate_home(7).to_dict() == generate_home(7).to_dict()
    dicts = [json.dumps(generate_home(seed).to_dict(), sort_keys=True) for seed in range(10)]
    assert len(set(dicts)) == 10


def test_dict_round_trip_through_json(homes: list[HomeSpec]) -> None:
    for home in homes[:5]:
        again = HomeSpec.from_dict(json.loads(json.dumps(home.to_dict())))
        assert again == home


def test_size_rooms_and_objects(homes: list[HomeSpec]) -> None:
    room_counts = Counter()
    for home in homes:
        names = [room.name for room in home.rooms]
        room_counts[len(names)] += 1
        assert 3 <= len(names) <= 5 and len(set(names)) == len(names)
        assert set(names) <= set(ROOM_TYPES)
        assert 40.0 <= home.area_m2 <= 90.0
        assert 10 <= len(home.objects) <= 14
        for item in home.objects:
            assert item.category in OBJECTS and item.colour in COLOURS and item.room in names
        ids = [label["id"] for label in home.labels().values()]
        assert sorted(ids) == list(range(1, len(ids) + 1))
    assert set(room_counts) == {3, 4, 5}


def test_n_rooms_is_respected_and_checked() -> None:
    for n in (3, 4, 5):
        assert len(generate_home(11, n_rooms=n).rooms) == n
    with pytest.raises(ValueError, match="n_rooms"):
        generate_home(11, n_rooms=9)


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
    closed = dataclasses.replace(home, walls=(*home.walls, Wall(999, (*door.center, 1.25), size)))
    assert dead_ends[0] not in reachable_rooms(closed, ROBOT_RADIUS)


def test_doorways_are_wide_and_kept_clear(homes: list[HomeSpec]) -> None:
    for home in homes:
        for door in home.doorways:
            assert 0.9 <= door.width <= 1.1
            zone = door.clear_zone(DOOR_CLEARANCE, side_margin=0.0)
            blocking = [f for f in home.furniture if rects_overlap(f.footprint, zone)]
            blocking += [o for o in home.objects if o.on is None and rects_overlap(o.footprint, zone)]
            assert not blocking, (home.seed, door, blocking)


def test_furniture_suits_its_room_and_objects_rest_on_something(homes: list[HomeSpec]) -> None:
    for home in homes:
        rooms = {room.name: room for room in home.rooms}
        pieces = {piece.instance_id: piece for piece in home.furniture}
        per_room = Counter(piece.room for piece in home.furniture)
        assert all(1 <= per_room[name] <= 2 for name in rooms), home.seed
        for piece in home.furniture:
            assert piece.room in FURNITURE[piece.category][1]
            x0, y0, x1, y1 = piece.footprint
            assert rooms[piece.room].contains(x0, y0) and rooms[piece.room].contains(x1, y1)
        for item in home.objects:
            half_height = item.half_extents[2]
            if item.on is None:
                assert item.center[2] == pytest.approx(half_height)
                assert rooms[item.room].contains(item.center[0], item.center[1])
            else:
                below = pieces[item.on]
                assert below.room == item.room
                assert item.center[2] == pytest.approx(below.top_z + half_height)
                fx0, fy0, fx1, fy1 = below.footprint
                ix0, iy0, ix1, iy1 = item.footprint
                assert fx0 <= ix0 and fy0 <= iy0 and ix1 <= fx1 and iy1 <= fy1
