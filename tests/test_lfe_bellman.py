"""The Bellman planner against brute force, the baselines, and the distance matrix on a tiny map."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from agent.lfe.bellman import (
    PLANNED_FRONTIERS,
    distance_matrix,
    greedy,
    largest,
    metres_to_steps,
    nearest,
    plan,
)
from agent.mapping.grid import GridSpec

SQRT2 = math.sqrt(2.0)
INF = math.inf


# --- brute force -------------------------------------------------------------------------------


def sequence_value(sequence: tuple[int, ...], area: np.ndarray, d_in: np.ndarray, d_out: np.ndarray,
                   distances: np.ndarray, sigma: float) -> tuple[float, bool]:
    """Area revealed by visiting the frontiers in this order, and whether a visit was cut short.

    Written forwards, as the robot lives it, independently of the planner's recursion.
    """
    node, total, partial = 0, 0.0, False
    for action in sequence:
        left = sigma - distances[node, action + 1]
        if left <= 0:
            break
        fraction = 1.0 if d_in[action] <= 0 else min(1.0, left / d_in[action])
        partial |= fraction < 1.0
        total += area[action] * fraction
        sigma = left - d_in[action] - d_out[action]
        node = action + 1
    return total, partial


def brute_force(area: np.ndarray, d_in: np.ndarray, d_out: np.ndarray, distances: np.ndarray,
                sigma: float) -> tuple[int, np.ndarray, bool]:
    """Every ordered subset: (choice by the paper's rules, best value per first action, partial?)."""
    k = len(area)
    q = np.zeros(k)
    partial_best = np.zeros(k, dtype=bool)
    for length in range(1, k + 1):
        for sequence in itertools.permutations(range(k), length):
            value, partial = sequence_value(sequence, area, d_in, d_out, distances, sigma)
            if value > q[sequence[0]]:
                q[sequence[0]], partial_best[sequence[0]] = value, partial
    after = sigma - distances[0, 1:] - d_in - d_out
    top = q.max()
    tied = [a for a in range(k) if abs(q[a] - top) <= 1e-9 * max(1.0, top)]
    choice = max(tied, key=lambda a: (after[a], -a))  # more steps left, then the lower index
    return choice, q, bool(partial_best[choice])


def random_problem(rng: np.random.Generator, k: int, integers: bool):
    """Frontiers as points in a room; integer data gives exact ties, floats give none."""
    points = rng.integers(0, 8, (k + 1, 2)) if integers else rng.random((k + 1, 2)) * 8
    distances = np.abs(points[:, None] - points[None]).sum(axis=2).astype(float)  # a city-block metric
    if rng.random() < 0.2:  # one frontier the robot cannot reach
        lost = int(rng.integers(1, k + 1))
        distances[lost, :] = distances[:, lost] = INF
        distances[lost, lost] = 0.0
    if integers:
        area = rng.integers(0, 6, k).astype(float)
        d_in = rng.integers(0, 6, k).astype(float)
        d_out = rng.integers(0, 6, k).astype(float)
        sigma = float(rng.integers(0, 40))
    else:
        area, d_in, d_out = rng.random(k) * 10, rng.random(k) * 8, rng.random(k) * 8
        sigma = float(rng.random() * 40)
    return area, d_in, d_out, distances, sigma


@pytest.mark.parametrize("integers", [True, False])
def test_plan_matches_brute_force(integers: bool) -> None:
    """Many small random frontier sets: same values, same choice (ties included), a best sequence."""
    partial_cases = 0
    for seed in range(400):
        rng = np.random.default_rng(seed)
        k = int(rng.integers(1, 6))
        area, d_in, d_out, distances, sigma = random_problem(rng, k, integers)
        choice, q, partial = brute_force(area, d_in, d_out, distances, sigma)
        result = plan(area, d_in, d_out, distances, sigma)
        np.testing.assert_allclose(result.q_values, q, rtol=1e-9, atol=1e-12, err_msg=f"seed {seed}")
        assert result.choice == choice, f"seed {seed}"
        assert result.value == pytest.approx(q[choice], rel=1e-9, abs=1e-12)
        assert result.sequence[0] == choice and len(set(result.sequence)) == len(result.sequence)
        value, _ = sequence_value(result.sequence, area, d_in, d_out, distances, sigma)
        assert value == pytest.approx(result.value, rel=1e-9, abs=1e-12), f"seed {seed}"
        partial_cases += partial and q[choice] > 0
    assert partial_cases > 20  # the min(1, ·) term was exercised, not only whole regions


def test_only_the_largest_frontiers_are_planned_over() -> None:
    """Eight frontiers, six planned: the answer is brute force over the six largest R_A."""
    rng = np.random.default_rng(7)
    area, d_in, d_out, distances, sigma = random_problem(rng, 8, integers=False)
    result = plan(area, d_in, d_out, distances, sigma)
    top = largest(area)
    assert len(top) == PLANNED_FRONTIERS
    nodes = np.concatenate([[0], top + 1])
    choice, q, _ = brute_force(area[top], d_in[top], d_out[top], distances[np.ix_(nodes, nodes)], sigma)
    assert result.choice == top[choice]
    np.testing.assert_allclose(result.q_values[top], q)
    assert np.isnan(np.delete(result.q_values, top)).all()


# --- cases worked by hand ----------------------------------------------------------------------


def one_frontier(sigma: float, d_k: float = 5.0):
    return plan([100.0], [10.0], [4.0], [[0.0, d_k], [d_k, 0.0]], sigma)


def test_partial_reward_when_time_runs_short() -> None:
    """Five steps to the frontier, ten to explore it, ten steps left: half of it is seen."""
    assert one_frontier(10.0).value == pytest.approx(50.0)
    assert one_frontier(15.0).value == pytest.approx(100.0)
    assert one_frontier(100.0).value == pytest.approx(100.0)


def test_nothing_for_a_frontier_out_of_reach_in_time() -> None:
    """σ − D_k ≤ 0 is worth nothing, never something negative."""
    for sigma in (5.0, 3.0, 0.0, -4.0):
        result = one_frontier(sigma)
        assert result.value == 0.0 and result.choice == 0 and result.sequence == (0,)
    assert plan([100.0], [10.0], [4.0], [[0.0, INF], [INF, 0.0]], 50.0).value == 0.0


def test_equal_values_go_to_the_frontier_that_leaves_more_steps() -> None:
    """Same area, same way there, same time in; the one that is quicker to leave wins, either index."""
    far = [[0.0, 5.0, 5.0], [5.0, 0.0, 100.0], [5.0, 100.0, 0.0]]  # the other is then out of reach
    assert plan([10.0, 10.0], [5.0, 5.0], [7.0, 3.0], far, 20.0).choice == 1
    assert plan([10.0, 10.0], [5.0, 5.0], [3.0, 7.0], far, 20.0).choice == 0
    assert plan([10.0, 10.0], [5.0, 5.0], [5.0, 5.0], far, 20.0).choice == 0  # full tie: lower index


def test_two_near_frontiers_beat_one_large_far_one() -> None:
    """Greedy goes for the large region and sees 40 % of it; the plan takes both small ones."""
    area, d_in, d_out = [10.0, 10.0, 15.0], [1.0, 1.0, 5.0], [1.0, 1.0, 1.0]
    distances = [[0, 1, 1, 10], [1, 0, 1, 10], [1, 1, 0, 10], [10, 10, 10, 0]]
    result = plan(area, d_in, d_out, distances, 12.0)
    assert greedy(area) == 2
    assert result.q_values[2] == pytest.approx(15.0 * 2 / 5 + 0.0)  # 2 of 5 steps, nothing after
    assert result.value == pytest.approx(20.0)
    assert result.choice == 0 and result.sequence == (0, 1)


def test_plan_rejects_bad_inputs() -> None:
    square = np.zeros((3, 3))
    with pytest.raises(ValueError, match="area"):
        plan([], [], [], np.zeros((1, 1)), 10.0)
    with pytest.raises(ValueError, match="d_in"):
        plan([1.0, 2.0], [1.0], [1.0, 1.0], square, 10.0)
    with pytest.raises(ValueError, match="d_out"):
        plan([1.0, 2.0], [1.0, 1.0], [1.0, -1.0], square, 10.0)
    with pytest.raises(ValueError, match="distances"):
        plan([1.0, 2.0], [1.0, 1.0], [1.0, 1.0], np.zeros((2, 2)), 10.0)
    with pytest.raises(ValueError, match="distances"):
        plan([1.0, 2.0], [1.0, 1.0], [1.0, 1.0], np.full((3, 3), np.nan), 10.0)
    with pytest.raises(ValueError, match="sigma"):
        plan([1.0, 2.0], [1.0, 1.0], [1.0, 1.0], square, INF)


# --- baselines ---------------------------------------------------------------------------------


def test_greedy_and_nearest() -> None:
    assert greedy([3.0, 9.0, 9.0, 1.0]) == 1
    assert nearest([4.0, INF, 2.5, 2.5]) == 2
    with pytest.raises(ValueError, match="from_robot"):
        nearest([INF, INF])
    with pytest.raises(ValueError, match="area"):
        greedy([])


# --- distances ---------------------------------------------------------------------------------


def test_distance_matrix_on_a_tiny_map() -> None:
    """Three rows, a wall in the middle row, a walled-off last column; 0.1 m cells.

        . . . . . # .
        . # # # . # .
        . . . . . # .

    Straight moves are one cell, diagonals √2 and may pass a wall's corner, as the planner drives.
    """
    spec = GridSpec((0.0, 0.0), 0.1, (3, 7))
    traversable = np.ones(spec.shape, dtype=bool)
    traversable[1, 1:4] = False
    traversable[:, 5] = False
    sources = [(0, 0), (2, 0), (0, 4), (2, 4), (1, 6)]
    d = 4 + SQRT2
    expected = 0.1 * np.array([
        [0, 2, 4, d, INF],
        [2, 0, d, 4, INF],
        [4, d, 0, 2, INF],
        [d, 4, 2, 0, INF],
        [INF, INF, INF, INF, 0],
    ])
    np.testing.assert_allclose(distance_matrix(spec, traversable, sources), expected)


def test_distance_matrix_can_leave_a_blocked_cell_but_not_enter_it() -> None:
    spec = GridSpec((0.0, 0.0), 0.1, (3, 7))
    traversable = np.ones(spec.shape, dtype=bool)
    traversable[1, 1:4] = False
    matrix = distance_matrix(spec, traversable, [(0, 0), (1, 2)])
    assert matrix[0, 1] == INF and matrix[1, 0] == pytest.approx(0.1 * (1 + SQRT2))


def test_distance_matrix_rejects_bad_inputs() -> None:
    spec = GridSpec((0.0, 0.0), 0.1, (3, 7))
    with pytest.raises(ValueError, match="traversable"):
        distance_matrix(spec, np.ones((3, 7)), [(0, 0)])
    with pytest.raises(ValueError, match="traversable"):
        distance_matrix(spec, np.ones((3, 6), dtype=bool), [(0, 0)])
    with pytest.raises(ValueError, match="sources"):
        distance_matrix(spec, np.ones((3, 7), dtype=bool), [(0, 0), (3, 0)])
    with pytest.raises(ValueError, match="sources"):
        distance_matrix(spec, np.ones((3, 7), dtype=bool), [])


def test_metres_to_steps() -> None:
    """0.25 m forward moves, 1.7 steps per move with the turns: 1 m is 6.8 steps."""
    np.testing.assert_allclose(metres_to_steps([1.0, 0.5, INF], 0.25), [6.8, 3.4, INF])
    with pytest.raises(ValueError, match="step_length_m"):
        metres_to_steps(1.0, 0.0)
