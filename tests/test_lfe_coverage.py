"""The coverage simulator: the sensor, the motion model, and whole explorations on small homes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.lfe.bellman import distance_matrix
from agent.lfe.coverage import fbe_near, run_coverage
from agent.lfe.motion import Action, stopping_cell, take_action
from agent.lfe.sensor import PanoramicSensor
from agent.lfe.task import CoverageConfig, Situation, TrueHome
from agent.mapping.grid import GridSpec
from agent.pose import Pose2D
from worlds.home import generate_home

RES = 0.05


def two_rooms(start_xy: tuple[float, float] = (0.8, 1.5), yaw: float = 0.0) -> TrueHome:
    """Two 2.8 x 2.8 m rooms side by side, a wall between them with a 1 m doorway in its middle."""
    occupied = np.zeros((60, 120), dtype=bool)
    occupied[:2] = occupied[-2:] = True
    occupied[:, :2] = occupied[:, -2:] = True
    occupied[:, 58:62] = True
    occupied[20:40, 58:62] = False
    return TrueHome(GridSpec((0.0, 0.0), RES, occupied.shape), ~occupied, occupied, start_xy, yaw)


def centre_distances(shape: tuple[int, int], cell: tuple[int, int]) -> np.ndarray:
    rows, cols = np.indices(shape)
    return np.hypot(rows - cell[0], cols - cell[1]) * RES


# --- the sensor ----------------------------------------------------------------------------------


def test_sensor_sees_all_round_up_to_its_range_and_no_farther() -> None:
    occupied = np.zeros((101, 101), dtype=bool)
    scan = PanoramicSensor(occupied, RES, 1.0).scan((50, 50))
    distance = centre_distances(occupied.shape, (50, 50))
    assert scan.free[distance <= 1.0 - RES].all()  # every direction, every cell within range
    assert not scan.free[distance > 1.0 + RES].any()
    assert not scan.occupied.any()


def test_a_wall_blocks_sight_and_is_seen_itself() -> None:
    occupied = np.zeros((41, 81), dtype=bool)
    occupied[:, 50:52] = True  # a wall 10 columns east of the sensor
    scan = PanoramicSensor(occupied, RES, 1.5).scan((20, 40))
    assert scan.occupied[20, 50] and not scan.occupied[20, 51]  # the face, not the wall's far side
    assert not scan.free[:, 50:].any()  # nothing behind it
    assert scan.free[20, 49] and scan.free[20, 30]
    assert not (scan.free & occupied).any()


def test_outside_the_grid_stops_rays_without_being_reported() -> None:
    occupied = np.zeros((10, 10), dtype=bool)
    scan = PanoramicSensor(occupied, RES, 2.0).scan((0, 0))
    assert scan.free.all() and not scan.occupied.any()


def test_sensor_refuses_a_cell_outside_the_grid() -> None:
    with pytest.raises(ValueError, match="cell"):
        PanoramicSensor(np.zeros((5, 5), dtype=bool), RES, 1.0).scan((5, 0))


# --- configuration and ground truth --------------------------------------------------------------


@pytest.mark.parametrize(("field", "value", "message"), [
    ("budget_steps", 0, "budget_steps: must be a positive integer, got 0"),
    ("replan_every", 1.5, "replan_every: must be a positive integer, got 1.5"),
    ("resolution", -0.05, "resolution: must be a positive number, got -0.05"),
    ("robot_radius_m", math.nan, "robot_radius_m: must be a positive number, got nan"),
    ("turn_deg", 200.0, "turn_deg: must be at most 180, got 200.0"),
    ("sensor_range_m", 0.01, "sensor_range_m: must be at least one cell"),
])
def test_config_names_the_bad_field(field: str, value: object, message: str) -> None:
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        CoverageConfig(**{field: value})


def test_true_home_refuses_a_start_off_the_floor_and_masks_of_another_shape() -> None:
    home = two_rooms()
    with pytest.raises(ValueError, match="start_xy"):
        TrueHome(home.spec, home.free, home.occupied, (0.02, 0.02), 0.0)  # inside the outer wall
    with pytest.raises(ValueError, match="free"):
        TrueHome(home.spec, home.free[:-1], home.occupied, home.start_xy, 0.0)


def test_a_generated_home_has_its_start_where_the_robot_fits_and_the_same_seed_gives_the_same() -> None:
    config = CoverageConfig()
    spec = generate_home(27)
    home = TrueHome.from_home(spec, config, seed=5)
    again = TrueHome.from_home(spec, config, seed=5)
    other = TrueHome.from_home(spec, config, seed=6)
    assert (home.start_xy, home.start_yaw) == (again.start_xy, again.start_yaw)
    assert (home.start_xy, home.start_yaw) != (other.start_xy, other.start_yaw)
    row, col = home.spec.to_cell(np.array(home.start_xy))
    clearance = min(np.hypot(*(np.argwhere(home.occupied) - [row, col]).T)) * RES
    assert clearance > config.robot_radius_m
    assert 0.6 * spec.area_m2 < home.area_m2 < spec.area_m2  # floor less what stands on it


# --- motion ---------------------------------------------------------------------------------------


def test_turns_change_only_the_heading_and_forward_moves_a_quarter_metre() -> None:
    home = two_rooms()
    clearance = home.clearance_m()
    pose = Pose2D(1.0, 1.5, 0.0)
    left, blocked = take_action(pose, Action.TURN_LEFT, clearance, home.spec)
    assert not blocked and (left.x, left.y) == (1.0, 1.5) and left.yaw == pytest.approx(math.radians(30))
    right, _ = take_action(pose, Action.TURN_RIGHT, clearance, home.spec)
    assert right.yaw == pytest.approx(-math.radians(30))
    ahead, blocked = take_action(left, Action.FORWARD, clearance, home.spec)
    assert not blocked
    assert (ahead.x, ahead.y) == pytest.approx((1.0 + 0.25 * math.cos(left.yaw), 1.5 + 0.25 * math.sin(left.yaw)))


def test_a_forward_move_into_a_wall_is_refused_and_the_pose_kept() -> None:
    home = two_rooms()
    clearance = home.clearance_m()
    facing_wall = Pose2D(2.56, 0.5, 0.0)  # 0.34 m from the dividing wall's face at x = 2.9, heading at it
    assert stopping_cell(facing_wall, clearance, home.spec) is not None
    after, blocked = take_action(facing_wall, Action.FORWARD, clearance, home.spec)
    assert blocked and after == facing_wall


def test_a_blocked_move_in_an_exploration_spends_a_step_and_leaves_the_robot_where_it_was() -> None:
    # A short sight and a wide robot: obstacles come into view only once the robot is nearly on them.
    config = CoverageConfig(sensor_range_m=0.5, robot_radius_m=0.4, budget_steps=100)
    result = run_coverage(two_rooms(), fbe_near, config)
    assert result.blocked_steps, "this configuration bumps into walls it has not seen"
    assert result.steps_used == 100
    for step in result.blocked_steps:
        np.testing.assert_array_equal(result.poses[step], result.poses[step - 1])


# --- whole explorations -----------------------------------------------------------------------------


def test_two_rooms_are_covered_and_exploration_ends_when_no_frontier_is_left() -> None:
    seen: list[tuple[Situation, int]] = []
    result = run_coverage(two_rooms(), fbe_near, on_plan=lambda situation, index: seen.append((situation, index)))
    assert result.exhausted
    assert result.coverage[-1] > 0.98
    assert len(result.coverage) == 501 and result.steps_used < 100
    assert (result.coverage[result.steps_used:] == result.coverage[result.steps_used]).all()  # padded
    assert (np.diff(result.coverage) >= 0).all() and 0 < result.coverage[0] and result.coverage.max() <= 1
    assert result.poses.shape == (result.steps_used + 1, 3)
    assert len(seen) == len(result.plan_seconds) == len(result.frontier_counts) >= 2
    # the east room was seen through the doorway, from the doorway at the farthest
    assert result.poses[:, 0].max() > 2.9


def test_situations_hold_the_partial_map_and_known_space_distances() -> None:
    home = two_rooms()
    seen: list[tuple[Situation, int]] = []
    run_coverage(home, fbe_near, CoverageConfig(budget_steps=40), on_plan=lambda s, i: seen.append((s, i)))
    first, index = seen[0]
    assert index == int(np.argmin(first.from_robot_m))
    assert first.steps_left == 40 and seen[-1][0].steps_left < 40
    np.testing.assert_array_equal(first.observed, first.free | first.occupied)
    assert not (first.free & home.occupied).any() and not (first.occupied & ~home.occupied).any()
    assert not first.observed[:, 62:].all()  # the east room is not all in view from the west one
    assert first.traversable[first.robot_cell] and not (first.traversable & ~first.free).any()
    matrix = distance_matrix(first.spec, first.traversable, [first.robot_cell] + [f.centre for f in first.frontiers])
    np.testing.assert_allclose(matrix[0, 1:], first.from_robot_m)
    assert np.isfinite(first.from_robot_m).all()
    # each situation is a snapshot: later sensing does not change an earlier one
    assert seen[-1][0].free.sum() > first.free.sum()


def test_any_chooser_gets_somewhere_and_a_bad_index_is_refused() -> None:
    farthest = run_coverage(two_rooms(), lambda s: int(np.argmax(s.from_robot_m)), CoverageConfig(budget_steps=150))
    assert farthest.coverage[-1] > 0.9
    with pytest.raises(ValueError, match="choose: returned 99"):
        run_coverage(two_rooms(), lambda s: 99, CoverageConfig(budget_steps=10))


def test_a_generated_home_is_explored_well_and_the_same_inputs_give_the_same_result() -> None:
    config = CoverageConfig(budget_steps=150)
    home = TrueHome.from_home(generate_home(27), config, seed=27)
    result = run_coverage(home, fbe_near, config)
    assert result.coverage[-1] > 0.8
    assert result.coverage[0] < 0.6  # it had to move to get there
    again = run_coverage(TrueHome.from_home(generate_home(27), config, seed=27), fbe_near, config)
    np.testing.assert_array_equal(result.coverage, again.coverage)
    np.testing.assert_array_equal(result.poses, again.poses)
    assert result.frontier_counts == again.frontier_counts

