"""Frames do not depend on whether the robot's own shapes are drawn: they are never in the picture.

The robot's shapes are loaded transparent (`worlds.body.UNSEEN`), which the tiny renderer skips.
Drawing them again, opaque, must leave every frame of a real home the same, pixel for pixel.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from worlds.camera import Frame
from worlds.freespace import free_space
from worlds.home import generate_home
from worlds.robot import ROBOT_RADIUS, CameraConfig
from worlds.sim import World

#: Random reachable spots, each looked from at a random heading.
VIEWS = 10


@pytest.fixture(scope="module")
def world() -> World:
    world = World(CameraConfig())
    world.build(generate_home(0, area_m2=300))
    yield world
    world.close()


def _views(world: World) -> list[tuple[float, float, float]]:
    assert world.home is not None
    space = free_space(world.home, ROBOT_RADIUS)
    cells = np.argwhere(space.components == space.main_component())
    rng = np.random.default_rng(0)
    picks = cells[rng.choice(len(cells), VIEWS, replace=False)]
    return [(*space.cell_centre(int(row), int(col)), float(rng.uniform(-math.pi, math.pi))) for row, col in picks]


def _frames(world: World, views: list[tuple[float, float, float]]) -> list[Frame]:
    frames = []
    for pose in views:
        world.place(pose)
        frames += [world.observe("head"), world.observe("wrist")]
    return frames


def _robot_alphas(world: World) -> set[float]:
    return {shape[7][3] for shape in p.getVisualShapeData(world.body.robot, physicsClientId=world.client)}


def test_frames_are_the_same_whether_or_not_the_robot_is_drawn(world: World) -> None:
    views = _views(world)
    assert _robot_alphas(world) == {0.0}
    unseen = _frames(world, views)
    links = {shape[1] for shape in p.getVisualShapeData(world.body.robot, physicsClientId=world.client)}
    for link in links:
        p.changeVisualShape(world.body.robot, link, rgbaColor=(1.0, 1.0, 1.0, 1.0), physicsClientId=world.client)
    assert _robot_alphas(world) == {1.0}
    drawn = _frames(world, views)
    assert sum(len(frame.labels) for frame in unseen) > VIEWS  # the views show the home, not nothing
    for a, b in zip(unseen, drawn, strict=True):
        assert np.array_equal(a.rgb, b.rgb)
        assert np.array_equal(a.depth, b.depth)
        assert np.array_equal(a.seg, b.seg)
        assert a.labels == b.labels
