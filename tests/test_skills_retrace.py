"""The way back along moves already made (`skills.arm.retrace.way_back`), from plain joint arrays."""

from __future__ import annotations

import numpy as np
import pytest

from skills.arm.retrace import way_back
from skills.arm.skill_plan import Step


def _move(start: list[float], end: list[float], count: int = 21) -> Step:
    samples = np.linspace(start, end, count)
    return Step("move", "m", samples, 0.01, samples[[0, -1]])


def test_the_way_back_runs_from_where_the_arm_stopped_back_through_every_move_to_the_first_s_start() -> None:
    lift, carry = _move([0.0, 0.0], [0.0, 1.0]), _move([0.0, 1.0], [2.0, 1.0])
    stopped = carry.samples[12] + [0.001, 0.0]  # partway through the carry, a little off its samples
    path = way_back([lift, carry], stopped, every=5)
    assert np.allclose(path[0], stopped)
    assert np.allclose(path[-1], [0.0, 0.0])  # where the lift began: the grasp
    assert np.allclose(path[1], carry.samples[12])  # back from where it stopped, not from the carry's end
    assert np.max(path[:, 0]) <= stopped[0] + 1e-9  # never on past where it stopped
    corner = int(np.argmin(np.linalg.norm(path - [0.0, 1.0], axis=1)))
    assert np.allclose(path[corner], [0.0, 1.0])  # through the corner between the moves
    assert np.all(np.abs(np.diff(path, axis=0)).max(axis=1) > 0)  # no two waypoints alike
    assert np.abs(np.diff(path, axis=0)).max() <= 5 * 0.1 + 1e-9  # every fifth sample at least


def test_a_stop_before_a_move_began_goes_back_through_the_moves_before_it() -> None:
    lift, carry = _move([0.0, 0.0], [0.0, 1.0]), _move([0.0, 1.0], [2.0, 1.0])
    path = way_back([lift, carry], np.array([0.0, 1.0]))
    assert np.allclose(path[0], [0.0, 1.0]) and np.allclose(path[-1], [0.0, 0.0])
    assert np.all(path[:, 0] == 0.0)


def test_no_moves_to_go_back_along_is_an_error() -> None:
    with pytest.raises(ValueError, match="moves with samples"):
        way_back([], np.zeros(2))
    with pytest.raises(ValueError, match="moves with samples"):
        way_back([Step("gripper", "close", action="close")], np.zeros(2))
