"""The PyBullet world without the bus: rendering under other camera settings, and collisions."""

from __future__ import annotations

import math
from collections.abc import Iterator

import numpy as np
import pytest

from worlds.robot import ROBOT_RADIUS, CameraConfig
from worlds.sim import MAX_STEP, World
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
    bottom = frame.depth[-5:]
    assert (bottom > 0).all()
    assert bottom.min() > sim.camera.mount_height_m * 0.9  # the floor ahead, not the robot's top
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
