"""Where the base stands to open storage in a room: clear of what the opening sweeps, in reach.

No world: the robot's own URDF in Pinocchio plans every opening, and the fronts are plain
geometry (doors in the plane y = 0 facing -y, hinged at x = 0).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.perception.part_geometry import PartGeometry, hinge_axis, part_geometry
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlanError
from skills.arm.stand import StandConfig, candidate_poses, choose_stand, hand_clearance, stand_pose, swept_clearance
from worlds.robot import CameraConfig
from worlds.robot_arm import robot_description

FACING_FRONT = math.pi / 2  # the base's yaw square on to a front facing -y


@pytest.fixture(scope="module")
def planner() -> ArmPlanner:
    return ArmPlanner.from_description(robot_description(CameraConfig()))


def _door(radius: float, height: float) -> PartGeometry:
    """A door hinged at x = 0 with its handle ``radius`` along the front, 5 cm short of its free edge."""
    handle, hinge, normal = np.array([radius, -0.035, height]), np.array([0.0, 0.0, height]), np.array([0.0, -1.0, 0.0])
    return PartGeometry("door", handle, np.array([0.0, 0.0, 1.0]), normal, hinge, hinge_axis(handle, hinge, normal),
                        radius + 0.05)


def _needed(planner: ArmPlanner) -> float:
    return planner.body_radius + StandConfig().margin_m


def test_a_door_s_width_is_read_off_its_front_from_the_hinge_to_the_free_edge() -> None:
    rng = np.random.default_rng(0)
    front = np.column_stack([rng.uniform(0.0, 0.6, 2000), np.zeros(2000), rng.uniform(0.2, 1.6, 2000)])
    handle = np.column_stack([np.full(200, 0.55), np.full(200, -0.04), rng.uniform(0.8, 1.0, 200)])
    door = part_geometry(handle + rng.normal(0, 0.002, handle.shape), front + rng.normal(0, 0.002, front.shape),
                         np.array([0.3, -1.5, 1.3]))
    assert door.kind == "door" and abs(door.hinge_point[0]) < 0.01
    assert door.width == pytest.approx(0.6, abs=0.02) and door.swing_radius == door.width


def test_standing_close_before_a_wide_door_the_robot_is_in_its_own_way() -> None:
    """The stand the act used to take: 0.85 m out, a third of the way from hinge to handle."""
    door = _door(0.6, 1.0)
    old = stand_pose(door, (0.3, -2.0, FACING_FRONT), distance_m=0.85)
    assert swept_clearance(door, math.radians(75.0), np.array(old[:2])) < 0.28  # inside the body


@pytest.mark.parametrize("radius, height", [(0.3, 0.5), (0.45, 0.8), (0.65, 1.0)])
def test_the_stand_keeps_hand_and_door_clear_of_the_body_and_the_opening_plans_from_it(
        planner: ArmPlanner, radius: float, height: float) -> None:
    door = _door(radius, height)
    stand = choose_stand(planner, planner.stowed, door)
    assert stand.amount == pytest.approx(math.radians(75.0))
    assert stand.pose[2] == pytest.approx(FACING_FRONT) and stand.pose[1] < -0.7
    assert stand.clearance_m >= _needed(planner)
    assert swept_clearance(door, stand.amount, np.array(stand.pose[:2])) >= _needed(planner)
    plan = planner.plan_open(planner.stowed, stand.pose, door, stand.amount)
    assert hand_clearance(planner, plan) >= _needed(planner)


def test_a_drawer_is_stood_before_square_on_level_with_its_handle(planner: ArmPlanner) -> None:
    drawer = PartGeometry("drawer", np.array([0.3, -0.035, 0.6]), np.array([1.0, 0.0, 0.0]), np.array([0.0, -1.0, 0.0]))
    stand = choose_stand(planner, planner.stowed, drawer)
    assert stand.pose[0] == pytest.approx(0.3) and stand.pose[2] == pytest.approx(FACING_FRONT)
    assert stand.amount == pytest.approx(0.2) and stand.clearance_m >= _needed(planner)


def test_candidates_beside_a_door_lie_between_its_handle_and_its_hinge() -> None:
    door = _door(0.5, 1.0)
    xs = {round(pose[0], 3) for pose in candidate_poses(door)}
    assert xs == {round(0.5 * (1 - share), 3) for share in StandConfig().hinge_shares}


def test_a_place_the_base_cannot_reach_is_not_stood_on(planner: ArmPlanner) -> None:
    door = _door(0.45, 0.8)
    with pytest.raises(SkillPlanError, match=r"stand: no place to open the door from \(12 unreachable"):
        choose_stand(planner, planner.stowed, door, reachable=lambda xy: False)
    right_of_handle = choose_stand(planner, planner.stowed, door, reachable=lambda xy: bool(xy[0] > 0.44))
    assert right_of_handle.pose[0] > 0.44
