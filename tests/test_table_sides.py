"""The four sides of the table a robot works at: the stands along each, facing the table, and the
way round the table between two of them, never across it."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.pose import Pose2D
from skills.table_sides import BACK, FRONT, LEFT, PASS_MARGIN_M, RIGHT, SIDES, TableSides


def _top(centre: tuple[float, float], size: tuple[float, float], step: float = 0.01) -> np.ndarray:
    """A level table's top seen from above: (N, 2) points on a grid over it, axis-aligned."""
    xs = np.arange(-size[0] / 2, size[0] / 2 + 1e-9, step) + centre[0]
    ys = np.arange(-size[1] / 2, size[1] / 2 + 1e-9, step) + centre[1]
    return np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)


#: A 1.4 m by 0.9 m table at the origin and a robot 0.28 m before its front side, facing it (+y).
START = Pose2D(0.1, -0.73, math.pi / 2)
TABLE = TableSides.around(_top((0.0, 0.0), (1.4, 0.9)), START)


def _outside(table: TableSides, point: np.ndarray, margin: float) -> bool:
    """Whether ``point`` lies outside the footprint grown by ``margin``."""
    local = table.local(FRONT, point)[0]
    return bool(abs(local[0]) >= table.half[0] + margin - 1e-9 or abs(local[1]) >= table.half[1] + margin - 1e-9)


def test_the_sides_are_measured_from_the_top_and_the_start() -> None:
    assert np.allclose(TABLE.centre, [0.0, 0.0], atol=1e-9)
    assert np.allclose(TABLE.half, [0.7, 0.45], atol=1e-9)
    assert TABLE.standoff == pytest.approx(0.28)
    # The front's line passes through the start, level with it: the robot stands there already.
    assert TABLE.stand(FRONT, float(TABLE.local(FRONT, START[:2])[0, 0])) == pytest.approx(START)


def test_each_side_s_stand_faces_the_table_from_the_standoff() -> None:
    expected = {FRONT: ((0.0, -0.73), math.pi / 2), RIGHT: ((0.98, 0.0), math.pi),
                BACK: ((0.0, 0.73), -math.pi / 2), LEFT: ((-0.98, 0.0), 0.0)}
    for side, (xy, yaw) in expected.items():
        stand = TABLE.stand(side, 0.0)
        assert stand[:2] == pytest.approx(xy, abs=1e-9), side
        assert math.remainder(stand.yaw - yaw, math.tau) == pytest.approx(0.0, abs=1e-9), side


def test_a_point_s_place_along_a_side_is_where_that_side_s_stand_is_level_with_it() -> None:
    point = np.array([0.3, 0.25])
    for side in SIDES:
        along, _ = TABLE.local(side, point)[0]
        stand = TABLE.stand(side, float(along))
        ahead = np.array([math.cos(stand.yaw), math.sin(stand.yaw)])
        offset = point - np.asarray(stand[:2])
        assert float(offset @ np.array([-ahead[1], ahead[0]])) == pytest.approx(0.0, abs=1e-9), side


def test_a_table_turned_with_the_start_is_measured_in_the_start_s_frame() -> None:
    # The same table turned a quarter turn, the robot facing it along +x from its -x side.
    start = Pose2D(-0.73, 0.1, 0.0)
    table = TableSides.around(_top((0.0, 0.0), (0.9, 1.4)), start)
    assert np.allclose(table.half, [0.7, 0.45], atol=1e-9)
    assert table.standoff == pytest.approx(0.28)
    assert table.stand(BACK, 0.0)[:2] == pytest.approx((0.73, 0.0), abs=1e-9)


def test_a_start_on_the_table_is_refused() -> None:
    with pytest.raises(ValueError, match="stands on the table's footprint"):
        TableSides.around(_top((0.0, 0.0), (1.4, 0.9)), Pose2D(0.0, 0.0, math.pi / 2))
    with pytest.raises(ValueError, match="top_xy"):
        TableSides.around(np.zeros((0, 2)), START)


def test_along_one_side_the_way_is_straight() -> None:
    assert TABLE.way(np.array(START[:2]), np.array([-0.5, -0.73])) == [(-0.5, -0.73)]
    # Backing away from the table, too.
    assert TABLE.way(np.array(START[:2]), np.array([0.1, -1.2])) == [(0.1, -1.2)]


@pytest.mark.parametrize("goal_side, goal_along, corners", [(BACK, 0.5, 2), (BACK, -0.5, 2), (RIGHT, 0.2, 1),
                                                             (LEFT, -0.3, 1)])
def test_to_another_side_the_way_goes_round_the_corners_and_never_across(goal_side: int, goal_along: float,
                                                                         corners: int) -> None:
    goal = TABLE.stand(goal_side, goal_along)
    way = TABLE.way(np.array(START[:2]), np.array(goal[:2]))
    assert way[-1] == pytest.approx(goal[:2])
    assert len(way) == corners + 1
    points = [np.array(START[:2]), *(np.array(xy) for xy in way)]
    for a, b in zip(points, points[1:]):
        for t in np.linspace(0.0, 1.0, 41):  # every point of the way stays off the table by the margin
            assert _outside(TABLE, a + t * (b - a), TABLE.standoff - PASS_MARGIN_M), (a, b, t)


def test_round_the_table_the_shorter_way_is_taken() -> None:
    # From the front's right end to the back's right end: round the right side, not the left.
    way = TABLE.way(np.array([0.6, -0.73]), np.array(TABLE.stand(BACK, -0.6)[:2]))
    assert all(x > 0 for x, _ in way[:-1])
    way = TABLE.way(np.array([-0.6, -0.73]), np.array(TABLE.stand(BACK, 0.6)[:2]))
    assert all(x < 0 for x, _ in way[:-1])
