"""A way through joint space around obstacles (`skills.arm.free_path`), on plain arrays: a
2-joint "arm" whose configurations are points in a square with a wall across it."""

from __future__ import annotations

import numpy as np

from skills.arm.free_path import connect, edge_clear, shortcut

LOWER, UPPER = np.array([-1.0, -1.0]), np.array([1.0, 1.0])


def _valid(q: np.ndarray) -> bool:
    """A wall at x = 0 from y = -1 up to y = 0.6: the way round goes over its top."""
    return not (abs(q[0]) < 0.1 and q[1] < 0.6)


def test_a_way_round_the_wall_is_found_and_every_step_of_it_is_clear() -> None:
    start, goal = np.array([-0.8, -0.8]), np.array([0.8, -0.8])
    assert not edge_clear(start, goal, _valid)
    path = connect(start, goal, _valid, LOWER, UPPER, np.random.default_rng(0))
    assert path is not None
    assert np.array_equal(path[0], start) and np.array_equal(path[-1], goal)
    assert all(edge_clear(a, b, _valid) for a, b in zip(path[:-1], path[1:]))
    assert max(q[1] for q in path) >= 0.6  # over the wall's top
    short = shortcut(path, _valid, np.random.default_rng(1))
    assert len(short) <= len(path)
    assert all(edge_clear(a, b, _valid) for a, b in zip(short[:-1], short[1:]))
    assert np.array_equal(short[0], start) and np.array_equal(short[-1], goal)


def test_the_same_generator_gives_the_same_way() -> None:
    start, goal = np.array([-0.8, -0.8]), np.array([0.8, -0.8])
    one = connect(start, goal, _valid, LOWER, UPPER, np.random.default_rng(7))
    two = connect(start, goal, _valid, LOWER, UPPER, np.random.default_rng(7))
    assert one is not None and two is not None
    assert all(np.array_equal(a, b) for a, b in zip(one, two)) and len(one) == len(two)


def test_a_straight_way_is_taken_as_it_is_and_a_walled_in_goal_is_refused() -> None:
    start, goal = np.array([-0.8, 0.8]), np.array([0.8, 0.8])
    assert connect(start, goal, _valid, LOWER, UPPER, np.random.default_rng(0)) == [start, goal]
    assert connect(start, np.array([0.0, 0.0]), _valid, LOWER, UPPER, np.random.default_rng(0)) is None
    boxed = connect(np.array([-0.8, -0.8]), np.array([0.8, -0.8]), lambda q: abs(q[0]) >= 0.1, LOWER, UPPER,
                    np.random.default_rng(0), max_samples=50)
    assert boxed is None  # a wall from edge to edge: no way at all


def test_an_edge_is_checked_finely_enough_not_to_step_over_what_is_as_thin_as_the_margin() -> None:
    # a band 12 mrad wide (1 cm at the hand, 0.85 m out) across the way, off the 0.04 rad grid
    def outside_band(q: np.ndarray) -> bool:
        return not 0.045 < q[0] < 0.057

    assert not edge_clear(np.zeros(2), np.array([0.4, 0.0]), outside_band)
