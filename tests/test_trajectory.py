"""Jerk-limited trajectories: limits checked by finite differences of the samples, exact waypoints,
durations no shorter than the velocity limits allow, and clear errors for bad input."""

from __future__ import annotations

import numpy as np
import pytest

from skills.arm.trajectory import JointLimits, JointTrajectory, plan_trajectory

TOLERANCE = 1.01  # finite differences of a jerk-limited motion stay within its limits; 1 % for rounding


def random_limits(dof: int, seed: int) -> JointLimits:
    rng = np.random.default_rng(seed)
    return JointLimits(rng.uniform(0.5, 2.0, dof), rng.uniform(2.0, 8.0, dof), rng.uniform(20.0, 80.0, dof))


def random_waypoints(count: int, dof: int, seed: int) -> np.ndarray:
    return np.cumsum(np.random.default_rng(seed).normal(0.0, 0.4, (count, dof)), axis=0)


def dense_line(count: int = 31) -> np.ndarray:
    """Closely spaced waypoints on a straight joint-space line, like a Cartesian path's."""
    start = np.array([0.3, 0.0, -0.3, 0.0, -2.2, 0.0, 1.9])
    return start + np.linspace(0.0, 1.0, count)[:, None] * np.array([0.2, 0.5, -0.3, 0.4, 0.6, -0.2, 0.3])


def assert_within_limits(trajectory: JointTrajectory, limits: JointLimits) -> None:
    positions, dt = trajectory.positions, trajectory.dt
    for order, bound in ((1, limits.velocity), (2, limits.acceleration), (3, limits.jerk)):
        derivative = np.diff(positions, n=order, axis=0) / dt**order
        worst = np.max(np.abs(derivative), axis=0) / bound
        assert np.all(worst <= TOLERANCE), f"derivative {order} reaches {worst.max():.4f} × its limit"
    assert np.all(np.abs(trajectory.velocities) <= limits.velocity * TOLERANCE)
    assert np.all(np.abs(trajectory.accelerations) <= limits.acceleration * TOLERANCE)


@pytest.mark.parametrize("pass_through", [False, True])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_limits_hold_and_waypoints_are_met(seed: int, pass_through: bool) -> None:
    limits = random_limits(7, seed)
    waypoints = random_waypoints(6, 7, seed + 10)
    trajectory = plan_trajectory(waypoints, limits, dt=0.004, pass_through=pass_through)
    assert_within_limits(trajectory, limits)
    np.testing.assert_array_equal(trajectory.positions[0], waypoints[0])
    np.testing.assert_array_equal(trajectory.positions[-1], waypoints[-1])
    np.testing.assert_array_equal(trajectory.velocities[-1], 0.0)
    assert len(trajectory.waypoint_times) == len(waypoints)
    assert np.all(np.diff(trajectory.waypoint_times) > 0)
    for time, waypoint in zip(trajectory.waypoint_times, waypoints, strict=True):
        np.testing.assert_allclose(trajectory.at(time)[0], waypoint, atol=1e-9)
        np.testing.assert_allclose(trajectory.at(time - 1e-7)[0], waypoint, atol=1e-6)  # continuous there
    assert trajectory.waypoint_times[-1] == trajectory.duration
    # no joint can be faster than its velocity limit, so none may arrive sooner
    travel = np.abs(np.diff(waypoints, axis=0))
    assert trajectory.duration >= np.max(travel.sum(axis=0) / limits.velocity)
    if not pass_through:  # stopping at each waypoint: every segment takes its slowest joint's time
        assert trajectory.duration >= np.sum(np.max(travel / limits.velocity, axis=1))


def test_samples_are_uniform_and_cover_the_duration() -> None:
    limits = random_limits(3, 3)
    trajectory = plan_trajectory(random_waypoints(3, 3, 4), limits, dt=0.01)
    np.testing.assert_allclose(np.diff(trajectory.times), 0.01)
    assert trajectory.times[0] == 0.0
    assert trajectory.times[-2] < trajectory.duration <= trajectory.times[-1]
    assert trajectory.positions.shape == trajectory.velocities.shape == trajectory.accelerations.shape
    assert trajectory.positions.shape == (len(trajectory.times), 3)
    # the sampled velocities are the derivatives of the sampled positions
    central = (trajectory.positions[2:] - trajectory.positions[:-2]) / 0.02
    np.testing.assert_allclose(central, trajectory.velocities[1:-1], atol=0.01 * limits.acceleration.max())


def test_passing_through_is_faster_and_does_not_overshoot() -> None:
    limits = random_limits(7, 5)
    waypoints = dense_line()
    stopping = plan_trajectory(waypoints, limits, dt=0.004, pass_through=False)
    passing = plan_trajectory(waypoints, limits, dt=0.004, pass_through=True)
    assert passing.duration < 0.6 * stopping.duration
    assert_within_limits(passing, limits)
    assert np.any(passing.waypoint_velocities[1:-1] != 0)
    np.testing.assert_array_equal(passing.waypoint_velocities[[0, -1]], 0.0)
    # every joint moves one way along the line, so its samples must be monotone
    steps = np.diff(passing.positions, axis=0) * np.sign(waypoints[-1] - waypoints[0])
    assert np.all(steps >= -1e-12)


def test_a_joint_turning_back_passes_its_waypoint_at_rest() -> None:
    limits = JointLimits.uniform(2, 1.0, 4.0, 40.0)
    waypoints = np.array([[0.0, 0.0], [1.0, 0.1], [2.0, 0.0]])  # the first joint sets the pace
    trajectory = plan_trajectory(waypoints, limits, dt=0.004)
    assert trajectory.waypoint_velocities[1, 0] > 0 and trajectory.waypoint_velocities[1, 1] == 0.0
    assert trajectory.duration < plan_trajectory(waypoints, limits, dt=0.004, pass_through=False).duration
    assert np.max(trajectory.positions[:, 1]) <= 0.1 + 1e-9  # the second joint never overshoots
    assert_within_limits(trajectory, limits)


def test_degenerate_waypoints() -> None:
    limits = JointLimits.uniform(2, 1.0, 4.0, 40.0)
    single = plan_trajectory(np.array([[0.1, 0.2]]), limits, dt=0.01)
    assert single.duration == 0.0 and single.positions.shape == (1, 2)
    np.testing.assert_array_equal(single.at(1.0)[0], [0.1, 0.2])
    repeated = plan_trajectory(np.array([[0.0, 0.0], [0.0, 0.0], [1.0, -1.0], [1.0, -1.0]]), limits, dt=0.01)
    np.testing.assert_array_equal(repeated.positions[-1], [1.0, -1.0])
    assert_within_limits(repeated, limits)


def test_limits_are_validated_by_field() -> None:
    with pytest.raises(ValueError, match=r"JointLimits.velocity\[1\] = -1.0"):
        JointLimits(np.array([1.0, -1.0]), np.ones(2), np.ones(2))
    with pytest.raises(ValueError, match=r"JointLimits.jerk\[0\] = 0.0"):
        JointLimits(np.ones(2), np.ones(2), np.zeros(2))
    with pytest.raises(ValueError, match=r"JointLimits.acceleration\[0\] = nan"):
        JointLimits(np.ones(1), np.array([np.nan]), np.ones(1))
    with pytest.raises(ValueError, match="differ in length"):
        JointLimits(np.ones(2), np.ones(3), np.ones(2))
    with pytest.raises(ValueError, match="JointLimits.velocity: expected a non-empty 1-D array"):
        JointLimits(np.ones((2, 2)), np.ones(2), np.ones(2))


def test_waypoints_and_period_are_validated_by_field() -> None:
    limits = JointLimits.uniform(2, 1.0, 4.0, 40.0)
    with pytest.raises(ValueError, match=r"waypoints: expected a non-empty \(n, dof\) array"):
        plan_trajectory(np.zeros(2), limits, dt=0.01)
    with pytest.raises(ValueError, match="waypoints: 3 joints, but limits are for 2"):
        plan_trajectory(np.zeros((2, 3)), limits, dt=0.01)
    with pytest.raises(ValueError, match=r"waypoints\[1, 0\] = inf is not finite"):
        plan_trajectory(np.array([[0.0, 0.0], [np.inf, 0.0]]), limits, dt=0.01)
    for dt in (0.0, -0.01, float("nan")):
        with pytest.raises(ValueError, match="dt: "):
            plan_trajectory(np.zeros((2, 2)), limits, dt=dt)
