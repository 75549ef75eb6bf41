"""The PyBullet world without the bus: rendering under other camera settings, and collisions."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

from worlds.drive import MAX_STEP
from worlds.robot import ROBOT_RADIUS, CameraConfig
from worlds.sight import visible_facts
from worlds.sim import World
from worlds.storage_placement import home_part_labels, home_storage
from worlds.things import point_rect_distance


@pytest.fixture
def sim() -> Iterator[World]:
    world = World(CameraConfig(width=160, height=120, hfov_deg=70.0, pitch_deg=-35.0))
    world.reset(5)
    yield world
    world.close()


def test_floor_back_projects_to_zero_height_with_other_camera_settings(sim: World) -> None:
    frame = sim.observe()
    camera = sim.camera
    rows, cols = np.indices(frame.depth.shape)
    z = frame.depth.astype(float)
    points = np.stack([(cols + 0.5 - camera.cx) * z / camera.fx, (rows + 0.5 - camera.cy) * z / camera.fy, z,
                       np.ones_like(z)], axis=-1) @ frame.camera_pose.T
    floors = [label["id"] for label in frame.labels if label["category"] == "floor"]
    mask = np.isin(frame.seg, floors) & (frame.depth > 0)
    assert mask.sum() > 500
    assert np.abs(points[..., 2][mask]).max() < 0.02


def test_same_seed_renders_the_same_frame(sim: World) -> None:
    again = World(sim.camera)
    try:
        again.reset(5)
        first, second = sim.observe(), again.observe()
        assert np.array_equal(first.rgb, second.rgb) and np.array_equal(first.seg, second.seg)
    finally:
        again.close()


def test_the_robot_never_sees_its_own_body(sim: World) -> None:
    frame = sim.observe()
    assert (frame.depth[-5:] > 0).all()
    assert (frame.seg[frame.depth > 0] >= 0).all()  # every surface hit is a labelled thing; the robot is not one
    assert sim.contact() is None  # observing leaves the body where it was


def test_moving_into_a_known_wall_stops_just_before_it(sim: World) -> None:
    home = sim.home
    x0, y0, x1, y1 = home.bounds
    for y in np.arange(y0 + 0.6, y1 - 0.6, 0.1):  # a row where the last stretch to the east wall is clear
        start = (x1 - 0.8, float(y), 0.0)
        sim.place(start)
        if sim.contact() is None and all(
            point_rect_distance(x, y, f.footprint) > ROBOT_RADIUS + 0.2
            for f in (*home.furniture, *home.objects)
            for x in np.arange(x1 - 0.8, x1, 0.05)
        ):
            break
    else:
        pytest.fail("no clear row to the east wall")
    result = sim.move_base([(x1 + 3.0, float(y))], yaw=math.pi)
    assert not result.reached and result.contact is not None and result.contact["category"] == "wall"
    east_wall_face = x1 - 0.05
    assert east_wall_face - ROBOT_RADIUS - MAX_STEP - 0.01 < result.base_pose[0] < east_wall_face - ROBOT_RADIUS
    assert result.base_pose[1] == pytest.approx(y) and result.base_pose[2] == pytest.approx(0.0)
    assert sim.contact() is None


def _home_with_something_in_a_drawer(world: World) -> tuple[int, str, int]:
    """Reset ``world`` to the first home with an object standing in a closed drawer: (piece, drawer, object)."""
    for seed in range(40):
        world.reset(seed)
        for item in world.home.objects:
            piece = next((f for f in world.home.furniture if f.instance_id == item.parent), None)
            if piece is None or piece.storage is None or item.slot is None:
                continue
            drawer = piece.storage.slot(item.slot).part
            if drawer is not None and piece.joints.get(drawer, 0.0) == 0.0:
                return piece.instance_id, drawer, item.instance_id
    pytest.fail("no home with an object in a closed drawer")


def test_storage_parts_start_at_the_homes_joint_states(sim: World) -> None:
    states = sim.part_states()
    pieces = {f.instance_id: f for f in sim.home.furniture if f.storage is not None}
    assert set(states) == set(pieces)
    for furniture_id, parts in states.items():
        piece = pieces[furniture_id]
        assert set(parts) == {part.name for part in piece.storage.parts}
        for name, value in parts.items():
            assert value == pytest.approx(piece.joints.get(name, 0.0), abs=1e-9)


def test_what_stands_in_a_drawer_moves_with_it(sim: World) -> None:
    piece_id, drawer, item_id = _home_with_something_in_a_drawer(sim)
    piece = next(f for f in sim.home.furniture if f.instance_id == piece_id)
    upper = piece.storage.part(drawer).upper
    before = np.array(sim.object_position(item_id))
    sim.set_part_state(piece_id, drawer, upper)
    moved = np.array(sim.object_position(item_id)) - before
    facing = np.array([math.cos(piece.facing), math.sin(piece.facing), 0.0])
    assert moved == pytest.approx(upper * facing, abs=1e-6)
    assert sim.part_states()[piece_id][drawer] == pytest.approx(upper)
    sim.set_part_state(piece_id, drawer, 0.0)
    assert np.array(sim.object_position(item_id)) == pytest.approx(before, abs=1e-6)


def test_a_hidden_object_shows_once_its_drawer_is_open(sim: World) -> None:
    piece_id, drawer, item_id = _home_with_something_in_a_drawer(sim)
    piece = next(f for f in sim.home.furniture if f.instance_id == piece_id)
    sim.set_part_state(piece_id, drawer, piece.storage.part(drawer).upper)
    x, y, _ = sim.object_position(item_id)
    heading = math.atan2(-math.sin(piece.facing), -math.cos(piece.facing))
    sim.place((x + 1.0 * math.cos(piece.facing), y + 1.0 * math.sin(piece.facing), heading))
    seen = sim.observe()
    sim.set_part_state(piece_id, drawer, 0.0)
    hidden = sim.observe()
    assert (seen.seg == item_id).any()
    assert not (hidden.seg == item_id).any()
    truth = {**sim.home.labels(), **home_part_labels(sim.home)}  # the drawer and its handle have ids of their own
    for frame in (seen, hidden):
        assert all({k: label[k] for k in truth[label["id"]]} == truth[label["id"]] for label in frame.labels)
    assert {"drawer", "handle"} <= {label["category"] for label in seen.labels}
    # What the camera shows now: the piece open, then closed, and the object seen inside it.
    states = [next(l.get("state") for l in frame.labels if l["id"] == piece_id) for frame in (seen, hidden)
              if any(l["id"] == piece_id for l in frame.labels)]
    assert states[0] == "open" and (len(states) == 1 or states[1] == "closed")
    assert next(l for l in seen.labels if l["id"] == item_id)["inside"] == piece.category


def test_set_part_state_rejects_what_is_not_there(sim: World) -> None:
    piece = next(f for f in sim.home.furniture if f.storage is not None)
    part = piece.storage.parts[0]
    plain = next((f for f in sim.home.furniture if f.storage is None), None)
    with pytest.raises(ValueError, match="part_name"):
        sim.set_part_state(piece.instance_id, "lid_9", 0.0)
    with pytest.raises(ValueError, match="outside"):
        sim.set_part_state(piece.instance_id, part.name, part.upper + 0.1)
    with pytest.raises(ValueError, match="furniture_id"):
        sim.set_part_state(plain.instance_id if plain else 10_000, part.name, 0.0)


def test_inside_is_said_only_where_the_frame_shows_the_open_storage_around_the_thing(sim: World) -> None:
    """A camera sees that a thing is in a drawer only when the drawer stands open and the drawer
    or its piece is in the same frame; a thing glimpsed alone, or behind a part shut since, is just
    a thing."""
    piece_id, drawer, item_id = _home_with_something_in_a_drawer(sim)
    piece = next(f for f in sim.home.furniture if f.instance_id == piece_id)
    [placement] = [p for p in home_storage(sim.home) if p.furniture_id == piece_id]
    drawer_id = placement.part_ids()[drawer]
    label = sim.home.labels()[item_id]
    shut = sim.part_states()
    sim.set_part_state(piece_id, drawer, piece.storage.part(drawer).upper)
    opened = sim.part_states()

    def inside(joints: dict, in_frame: set[int]) -> str | None:
        return visible_facts(sim.stage, label, joints, in_frame).get("inside")

    assert inside(opened, {item_id, piece_id}) == piece.category
    assert inside(opened, {item_id, drawer_id}) == piece.category  # looking down into the drawer
    assert inside(opened, {item_id}) is None  # the storage is out of the frame
    assert inside(shut, {item_id, piece_id, drawer_id}) is None  # shut
