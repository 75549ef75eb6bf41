"""A straight drive with the arm out keeps the hand off the doors and drawers the robot left open, and an
arm that would stand in one where the base is going is folded in first, where its fold keeps clear."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skills.arm.arm_model import READY
from skills.arm.clearance import Clearance
from skills.arm.drive_clear import CLEAR_M, FOLD_BACK_M, clear_path, fold_place
from skills.arm.fold_plans import plan_stow
from skills.arm.frames import base_transform
from skills.arm.planner import ArmPlanner
from worlds.robot import CameraConfig
from worlds.robot_arm import robot_description

#: The base faces the table (+y) from y = -0.8 and slides along its edge, the hand 0.45 m ahead of it.
HERE, THERE = (0.0, -0.8, math.pi / 2), (0.6, -0.8, math.pi / 2)
HAND = np.array([[x, y, z] for x in (-0.04, 0.04) for y in (-0.4, -0.33) for z in (0.9, 1.05)])


def _door(x: float, front_y: float) -> np.ndarray:
    """A door swung open towards the robot: a vertical board along y, from the carcass out to ``front_y``."""
    return np.array([[x, y, z] for y in np.arange(front_y, 0.05, 0.01) for z in (0.8, 0.95, 1.1)])


def test_a_door_standing_open_across_the_hand_s_way_is_passed_behind() -> None:
    door = _door(0.3, front_y=-0.3)  # its free edge 3 cm beyond the hand's front
    path = clear_path(HERE, THERE, HAND, [door])
    assert len(path) == 3 and path[-1] == pytest.approx(THERE[:2])
    start, end = np.array(path[0]), np.array(path[1])
    assert start[0] == pytest.approx(0.0) and end[0] == pytest.approx(0.6) and start[1] == pytest.approx(end[1])
    # backed away until the door's nearest point stands CLEAR_M ahead of the hand's front
    hand_front = HAND[:, 1].max() - HERE[1]
    assert -0.3 - start[1] == pytest.approx(hand_front + CLEAR_M)
    for t in np.linspace(0, 1, 31):  # and along the way, the hand's box never comes within CLEAR_M of it
        base = start + t * (end - start)
        hand = HAND[:, :2] - np.array(HERE[:2]) + base
        inside = ((door[:, 0] > hand[:, 0].min() - CLEAR_M + 1e-9) & (door[:, 0] < hand[:, 0].max() + CLEAR_M - 1e-9)
                  & (door[:, 1] > hand[:, 1].min() - CLEAR_M + 1e-9) & (door[:, 1] < hand[:, 1].max() + CLEAR_M - 1e-9))
        assert not inside.any()


@pytest.mark.parametrize("standing_open", [
    [],  # nothing open
    [_door(0.9, front_y=-0.3)],  # open beyond where the base goes
    [_door(0.3, front_y=-0.1)],  # open, but its edge well ahead of the hand
    [_door(0.3, front_y=-0.3) + [0.0, 0.0, 0.5]],  # above the hand's height
])
def test_a_clear_way_is_driven_straight(standing_open) -> None:
    assert clear_path(HERE, THERE, HAND, standing_open) == [pytest.approx(THERE[:2])]


@pytest.fixture(scope="module")
def planner() -> ArmPlanner:
    return ArmPlanner.from_description(robot_description(CameraConfig()))


def test_an_arm_that_would_stand_in_an_open_door_is_folded_where_the_fold_keeps_clear_of_it(
        planner: ArmPlanner) -> None:
    # recursive 1008, drawer-door 1011 (tuning-wide): coming back to the stand of a door it had
    # opened, its arm out as a look elsewhere had left it, the robot drove the arm into the door.
    q = np.array(READY)
    way = [[0.0, -1.0], [0.6, -1.0], [0.6, -0.8]]  # backed away 0.2 m, along, and forward onto THERE
    hand = (base_transform(THERE) @ planner.kin.forward(q))[:3, 3]
    door = _door(hand[0] + 0.02, front_y=hand[1] - 0.05) + np.array([0.0, 0.0, hand[2] - 0.95])
    assert Clearance(planner, base_transform(THERE), None, door).problem(q, hand=True) is not None
    folded_at = fold_place(planner, q, way, THERE, math.pi / 2, [door], surface_z=None)
    assert folded_at is not None
    back = folded_at[0][1] - way[0][1]
    assert back in [pytest.approx(-extra) for extra in FOLD_BACK_M]
    assert folded_at[1] == pytest.approx([way[1][0], way[1][1] + back])
    backed = (folded_at[1][0], folded_at[1][1], math.pi / 2)
    fold = plan_stow(planner, q, backed)
    clearance = Clearance(planner, base_transform(backed), None, door)
    assert all(clearance.path_problem(step.samples, hand=True) is None for step in fold.steps if step.kind == "move")
    # an arm clear of the door where the base is going is not folded, nor on a straight drive
    aside = door + np.array([1.0, 0.0, 0.0])
    assert fold_place(planner, q, way, THERE, math.pi / 2, [aside]) is None
    assert fold_place(planner, q, [list(THERE[:2])], THERE, math.pi / 2, [door]) is None
