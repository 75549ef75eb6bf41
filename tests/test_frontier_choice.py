"""Choosing the next frontier: the paper's fresh draw, and the default that weighs distance and commits."""

from __future__ import annotations

import numpy as np
import pytest

from agent.app.config import ConfigError, load_config
from agent.planning.frontier_choice import FrontierChoiceConfig, choose_frontier

#: Two frontiers of equal weight, one 2 m away and one 12 m away, on opposite sides.
CENTRES = np.array([[2.0, 0.0], [-12.0, 0.0]])
DISTANCES = np.array([2.0, 12.0])
EQUAL = np.zeros(2)


def _draws(config: FrontierChoiceConfig, log_weights: np.ndarray | None, goal=None, n: int = 400) -> np.ndarray:
    rng = np.random.default_rng(3)
    return np.array([choose_frontier(CENTRES, DISTANCES, log_weights, goal, config, rng) for _ in range(n)])


def test_the_papers_rule_draws_equal_weights_evenly_whatever_the_distance() -> None:
    draws = _draws(FrontierChoiceConfig(rule="sample"), EQUAL)
    assert 0.4 < (draws == 1).mean() < 0.6


def test_the_default_prefers_the_nearer_of_equally_weighted_frontiers() -> None:
    draws = _draws(FrontierChoiceConfig(), EQUAL)
    assert (draws == 0).mean() > 0.9  # e^(0.25·10) ≈ 12 to 1


def test_a_much_better_far_frontier_still_wins() -> None:
    draws = _draws(FrontierChoiceConfig(), np.array([0.0, 5.0]))
    assert (draws == 1).mean() > 0.9


def test_the_goal_is_kept_while_it_is_there_even_when_another_is_nearer() -> None:
    goal = np.array([-11.6, 0.3])  # the far frontier, moved a little as the map grew
    draws = _draws(FrontierChoiceConfig(), EQUAL, goal)
    assert (draws == 1).all()


def test_the_goal_is_given_up_for_a_clearly_better_frontier() -> None:
    goal = np.array([-12.0, 0.0])
    draws = _draws(FrontierChoiceConfig(switch_margin=1.5), np.array([8.0, 0.0]), goal)
    assert (draws == 0).all()


def test_a_goal_that_is_gone_means_a_fresh_choice() -> None:
    goal = np.array([0.0, 9.0])  # no candidate within a metre of it: explored or unreachable now
    draws = _draws(FrontierChoiceConfig(), EQUAL, goal)
    assert (draws == 0).mean() > 0.9


def test_fbe_takes_the_nearest_and_keeps_its_goal() -> None:
    assert set(_draws(FrontierChoiceConfig(), None, n=5)) == {0}
    assert set(_draws(FrontierChoiceConfig(rule="sample"), None, np.array([-12.0, 0.0]), n=5)) == {0}
    assert set(_draws(FrontierChoiceConfig(), None, np.array([-12.0, 0.0]), n=5)) == {1}


def test_no_candidate_is_no_choice() -> None:
    rng = np.random.default_rng(0)
    assert choose_frontier(np.zeros((0, 2)), np.zeros(0), None, None, FrontierChoiceConfig(), rng) is None


def test_same_seed_same_choices() -> None:
    config = FrontierChoiceConfig()
    assert _draws(config, np.array([0.0, 2.4])).tolist() == _draws(config, np.array([0.0, 2.4])).tolist()


@pytest.mark.parametrize("override, field", [
    ("explore.choice.rule=nearest", "frontier_choice.rule"),
    ("explore.choice.distance_cost_per_m=-1", "explore.choice.distance_cost_per_m"),
    ("explore.choice.switch_margin=NaN", "explore.choice.switch_margin"),
])
def test_bad_settings_are_refused_by_name(override: str, field: str) -> None:
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        load_config(None, [override])
