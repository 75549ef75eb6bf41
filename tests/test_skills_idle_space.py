"""Idle space: free spots on a table for what is picked away, from plain point arrays."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skills.arm.idle_space import idle_spot, reach_along, stack_spot
from skills.arm.skill_plan import SkillPlanError


def _table() -> np.ndarray:
    xs, ys = np.meshgrid(np.arange(-0.6, 0.6, 0.01), np.arange(-0.4, 0.4, 0.01))
    return np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 0.75)])


def test_an_idle_spot_is_on_the_surface_clear_of_everything_standing_on_it() -> None:
    table = _table()
    angles = np.linspace(0, 2 * math.pi, 40)
    can = np.column_stack([0.1 + 0.033 * np.cos(angles), 0.033 * np.sin(angles), np.full(40, 0.8)])
    flat_thing = np.column_stack([np.full(5, 0.3), np.linspace(-0.1, 0.1, 5), np.full(5, 0.752)])  # not standing up
    spot = idle_spot(table, [can, flat_thing], 0.035, (0.12, 0.0))
    assert spot[2] == pytest.approx(0.75)
    assert np.min(np.linalg.norm(can[:, :2] - spot[:2], axis=1)) >= 0.11 + 0.03 - 1e-9  # the hand's reach
    assert np.linalg.norm(spot[:2] - [0.12, 0.0]) < 0.2  # and otherwise as near as asked
    assert -0.6 + 0.065 <= spot[0] <= 0.59 - 0.065 and -0.4 + 0.065 <= spot[1] <= 0.39 - 0.065
    with pytest.raises(SkillPlanError, match="too small"):
        idle_spot(table[np.abs(table[:, 0]) < 0.03], [], 0.035, (0.0, 0.0))



def test_a_spot_beyond_the_arm_s_reach_is_not_offered() -> None:
    table = _table()
    base = np.array([0.0, -0.9])  # the robot at the table's near edge (y = -0.4)

    def within(places: np.ndarray, distance: float) -> np.ndarray:
        return np.linalg.norm(places - base, axis=1) <= distance

    spot = idle_spot(table, [], 0.035, (0.5, 0.3), allowed=lambda places: within(places, 0.8),
                     allowed_means="within reach")
    assert np.linalg.norm(spot[:2] - base) <= 0.8
    with pytest.raises(SkillPlanError, match="no free place .* within reach"):
        idle_spot(table, [], 0.035, (0.0, 0.0), allowed=lambda places: within(places, 0.4),
                  allowed_means="within reach")


def test_the_stands_reaching_a_point_are_an_interval_along_the_edge() -> None:
    lo, hi = reach_along(np.array([[0.3, -0.1], [1.0, 0.7], [0.0, -0.9]]), -0.9, 1.0)
    assert lo[0] == pytest.approx(0.3 - 0.6) and hi[0] == pytest.approx(0.3 + 0.6)  # 0.8 m out: 0.6 either way
    assert lo[1] > hi[1]  # 1.6 m out: no stand reaches it
    assert (lo[2], hi[2]) == pytest.approx((-1.0, 1.0))


def test_things_lower_than_where_the_hand_works_keep_only_the_object_s_own_room() -> None:
    table = _table()
    soap = np.column_stack([np.full(9, 0.1), np.linspace(-0.03, 0.03, 9), np.full(9, 0.78)])  # 3 cm tall
    bottle = np.column_stack([np.full(9, -0.3), np.linspace(-0.02, 0.02, 9), np.full(9, 0.99)])
    near = (0.16, 0.0)
    spot = idle_spot(table, [soap, bottle], 0.04, near, height=0.12)  # a box 12 cm tall: the hand above the soap
    gap = float(np.min(np.linalg.norm(soap[:, :2] - spot[:2], axis=1)))
    assert 0.04 + 0.03 - 1e-9 <= gap < 0.11 + 0.03
    assert float(np.min(np.linalg.norm(bottle[:, :2] - spot[:2], axis=1))) >= 0.11 + 0.03 - 1e-9
    unknown = idle_spot(table, [soap, bottle], 0.04, near)  # no height: everything counts for the hand
    assert float(np.min(np.linalg.norm(soap[:, :2] - unknown[:2], axis=1))) >= 0.11 + 0.03 - 1e-9
    flat = idle_spot(table, [soap], 0.04, near, height=0.05)  # as low as the soap: the hand meets it
    assert float(np.min(np.linalg.norm(soap[:, :2] - flat[:2], axis=1))) >= 0.11 + 0.03 - 1e-9


def test_several_spots_come_nearest_first_and_apart() -> None:
    spots = idle_spot(_table(), [], 0.035, (0.0, 0.0), count=3, apart_m=0.15)
    assert spots.shape == (3, 3)
    distances = np.linalg.norm(spots[:, :2], axis=1)
    assert list(distances) == sorted(distances) and distances[0] < 0.02
    assert min(np.linalg.norm(spots[i, :2] - spots[j, :2]) for i in range(3) for j in range(i + 1, 3)) >= 0.15


def _box_top(centre: tuple[float, float], side: float, top: float) -> np.ndarray:
    xs, ys = np.meshgrid(np.arange(-side / 2, side / 2 + 1e-9, 0.01), np.arange(-side / 2, side / 2 + 1e-9, 0.01))
    walls = np.column_stack([np.full(20, centre[0] - side / 2), np.full(20, centre[1]), np.linspace(0.75, top, 20)])
    return np.vstack([np.column_stack([xs.ravel() + centre[0], ys.ravel() + centre[1], np.full(xs.size, top)]), walls])


def test_an_object_goes_on_a_flat_top_as_wide_as_it_and_bare() -> None:
    box = _box_top((-0.2, -0.25), 0.32, 0.847)
    spot = stack_spot(box, [], (0.28, 0.28, 0.07))
    assert spot is not None
    assert spot[:2] == pytest.approx((-0.2, -0.25), abs=0.006) and spot[2] == pytest.approx(0.847, abs=0.003)
    assert stack_spot(box, [], (0.36, 0.28, 0.07)) is None  # wider than the top, past the overhang allowed
    cup = np.array([[-0.15, -0.2, 0.9], [-0.15, -0.21, 0.93]])
    assert stack_spot(box, [cup], (0.28, 0.28, 0.07)) is None  # something stands on it already
    beside = cup + np.array([0.4, 0.0, 0.0])
    assert stack_spot(box, [beside], (0.28, 0.28, 0.07)) is not None
    assert stack_spot(box[:5], [], (0.1, 0.1, 0.05)) is None  # too few points to know its top

