"""After a thing is lifted out of a door or drawer standing open, the wrist camera looks in again:
what it covered there lies below the drawer's sides for the head camera."""

from __future__ import annotations

import numpy as np
import pytest

from agent.perception.part_geometry import PartGeometry
from agent.pose import Pose2D
from skills.robot import Robot
from skills.robot_parts import Opened
from test_robot_keep_off import NoWorld, _remember

#: Where the wrist camera looks into the open drawer (as `DoorsAndDrawers.open_part` left it).
LOOK = np.array([0.0, 0.1, 0.8])


@pytest.fixture
def robot(monkeypatch: pytest.MonkeyPatch) -> tuple[Robot, list[np.ndarray]]:
    """A robot that remembers a chest with its lower drawer pulled 0.15 m out and a box standing
    beside the chest, and that records where the wrist camera is sent (no world to look at)."""
    robot = Robot(NoWorld())  # type: ignore[arg-type]
    _remember(robot, "table", (0.0, 0.3, 0.745), (1.2, 0.8, 0.02))
    chest = _remember(robot, "drawer chest", (0.0, 0.4, 0.9), (0.4, 0.3, 0.3))
    drawer = _remember(robot, "drawer", (0.0, 0.1, 0.82), (0.36, 0.3, 0.1), chest)
    geometry = PartGeometry("drawer", np.array([0.0, 0.23, 0.82]), np.array([1.0, 0.0, 0.0]),
                            np.array([0.0, -1.0, 0.0]))
    robot.parts.opened[drawer.id] = Opened(geometry, 0.15, Pose2D(0.0, -0.6, np.pi / 2), LOOK)
    looked: list[np.ndarray] = []
    monkeypatch.setattr(robot.parts, "_look_into", looked.append)
    return robot, looked


def _box(centre, size=(0.1, 0.1, 0.06)) -> tuple[np.ndarray, np.ndarray]:
    centre, half = np.asarray(centre, float), np.asarray(size, float) / 2
    return centre - half, centre + half


def test_a_thing_lifted_out_of_an_open_drawer_is_followed_by_a_look_into_it(robot) -> None:
    robot, looked = robot
    assert "drawer" in robot.parts.look_inside
    assert robot.parts.look_again_into(_box((0.05, 0.12, 0.83)))  # in the tray, out before the chest
    assert len(looked) == 1 and np.allclose(looked[0], LOOK)


@pytest.mark.parametrize("centre", [(0.45, 0.1, 0.8), (0.0, -0.3, 0.8), (0.0, 0.4, 1.12)])
def test_a_thing_beside_on_before_or_on_top_of_the_chest_is_not(robot, centre) -> None:
    robot, looked = robot
    assert not robot.parts.look_again_into(_box(centre))
    assert looked == []


def test_nor_one_from_a_drawer_shut_again(robot) -> None:
    robot, looked = robot
    part_id, opened = next(iter(robot.parts.opened.items()))
    robot.parts.opened[part_id] = Opened(opened.geometry, 0.0, opened.stand, opened.look_point)
    assert not robot.parts.look_again_into(_box((0.05, 0.12, 0.83)))
    assert looked == []
