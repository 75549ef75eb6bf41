"""Picking from the side of the table that reaches the thing: a nest at the table's back, beyond
the arm's reach from the front, is picked from the back, at a stand where the arm comes out of the
base clear of the storage standing there; and a thing put down is picked back by the point it was
put down by unless the memory shows it moved."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.pose import Pose2D
from skills.arm.clearance import box_points
from skills.arm.fold_plans import unfold_problem
from skills.arm.planner import ArmPlanner
from skills.robot import Robot
from skills.robot_picks import _moved
from skills.table_sides import BACK, FRONT, LEFT, RIGHT
from test_robot_keep_off import NoWorld, _remember
from worlds.robot import CameraConfig
from worlds.robot_arm import robot_description


@pytest.fixture(scope="module")
def planner() -> ArmPlanner:
    return ArmPlanner.from_description(robot_description(CameraConfig()))


def _robot_at_table(planner: ArmPlanner | None = None) -> Robot:
    """A robot 0.28 m before the front (y = -0.45) of a 1.4 m by 0.9 m table at the origin."""
    robot = Robot(NoWorld())  # type: ignore[arg-type]
    robot.body.home = Pose2D(0.0, -0.73, math.pi / 2)
    robot.body.context.planner = planner
    _remember(robot, "table", (0.0, 0.0, 0.745), (1.4, 0.9, 0.02))
    return robot


def test_a_thing_within_the_front_s_reach_is_picked_from_the_front_first() -> None:
    robot = _robot_at_table()
    table = robot.body.table_sides()
    assert table is not None
    sides = [side for side, _ in robot.picks.stands_and_spots.sides(table, np.array([0.5, 0.0, 0.8]))]
    assert sides[0] == FRONT and set(sides) == {FRONT, RIGHT, BACK}  # the left side is 1.18 m from it


def test_a_thing_at_the_table_s_back_is_tried_from_the_front_then_from_the_nearest_sides_that_reach_it() -> None:
    robot = _robot_at_table()
    table = robot.body.table_sides()
    assert table is not None
    # 1.03 m from the front's line, tried from level with it there first (the arm may still reach
    # it); from the back, 0.43 m out; from the left, 0.48 m.
    sides = robot.picks.stands_and_spots.sides(table, np.array([-0.5, 0.3, 0.8]))
    assert [side for side, _ in sides] == [FRONT, BACK, LEFT]
    assert sides[0][1] == (pytest.approx(-0.5, abs=0.01), pytest.approx(-0.5, abs=0.01))
    # In storage, or with a part standing open: from the front alone, which storage opens to.
    assert robot.picks.stands_and_spots.sides(table, np.array([-0.5, 0.3, 0.8]), front_only=True) == [
        (FRONT, (pytest.approx(-0.5, abs=0.01), pytest.approx(-0.5, abs=0.01)))]
    # Nowhere within reach (a table too deep all round): the front, level with the thing.
    robot = Robot(NoWorld())  # type: ignore[arg-type]
    robot.body.home = Pose2D(0.0, -1.28, math.pi / 2)
    _remember(robot, "table", (0.0, 0.0, 0.745), (2.4, 2.0, 0.02))
    deep = robot.body.table_sides()
    assert deep is not None
    assert robot.picks.stands_and_spots.sides(deep, np.array([0.3, 0.0, 0.8])) == [(FRONT, (pytest.approx(0.3, abs=0.01), pytest.approx(0.3, abs=0.01)))]


def test_the_arm_comes_out_of_the_base_clear_only_where_nothing_stands_right_before_it(planner: ArmPlanner) -> None:
    base = Pose2D(0.0, 0.0, math.pi / 2)
    chest_before = box_points(np.array([0.0, 0.45, 0.75]), np.array([0.4, 0.3, 0.35]))  # its front 0.3 m ahead
    assert unfold_problem(planner, base, chest_before) is not None
    chest_further = box_points(np.array([0.0, 0.6, 0.75]), np.array([0.4, 0.3, 0.35]))  # 0.45 m ahead
    assert unfold_problem(planner, base, chest_further) is None
    assert unfold_problem(planner, base, np.zeros((0, 3))) is None


def test_a_stand_at_the_back_slides_along_to_where_the_arm_comes_out_clear_of_the_storage(planner: ArmPlanner) -> None:
    robot = _robot_at_table(planner)
    # A drawer chest at the table's back edge, right before the back's stand level with x = -0.1.
    _remember(robot, "drawer_chest", (-0.1, 0.29, 0.93), (0.4, 0.32, 0.35))
    table = robot.body.table_sides()
    assert table is not None
    level = float(table.local(BACK, np.array([[-0.1, 0.0]]))[0, 0])
    along = robot.picks.stands_and_spots.clear_stand(table, BACK, level, level - 0.6, level + 0.6)
    stand = table.stand(BACK, along)
    assert abs(stand.x - (-0.1)) > 0.2  # beside the chest, not before it
    assert unfold_problem(planner, stand, robot.body.points_near(())) is None
    with pytest.raises(Exception, match="no stand at the table's back"):
        robot.picks.stands_and_spots.clear_stand(table, BACK, level, level - 0.05, level + 0.05)


def test_a_box_seen_whole_once_put_down_has_not_moved_but_one_pushed_aside_has() -> None:
    before = (np.array([0.0, 0.0, 0.75]), np.array([0.10, 0.13, 0.89]))
    grown = (np.array([0.0, 0.0, 0.75]), np.array([0.13, 0.13, 0.89]))  # its far side seen at last
    assert np.allclose(_moved(before, grown), 0.0)
    pushed = (np.array([0.05, -0.01, 0.75]), np.array([0.16, 0.12, 0.89]))
    assert np.allclose(_moved(before, pushed), [0.05, -0.01])
