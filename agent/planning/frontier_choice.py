"""Which frontier to head for this step, given each one's weight and path length.

The paper samples the next frontier in proportion to its weight, afresh every step (``sample``).
Measured on generated homes, that makes the robot wander: when the semantic values barely differ
(a view of a corridor, a question about a small thing) the draw is near uniform over frontiers
all over the map, the robot drives its 3 m toward one, and the next step draws another, often
back the way it came. Frontier-based exploration has a milder form of it: the nearest frontier
changes as the map grows, and the robot turns back to whatever is nearest now.

``committed`` (the default) keeps what the paper's weights say and adds what its authors' code
adds, the cost of getting there: a fresh choice is drawn ∝ w_p·exp(−λ·d_p) (FBE: the nearest),
and the robot then keeps heading for the frontier it chose until it is reached or gone, unless
another frontier's log weight beats it by ``switch_margin`` (a view that made a place clearly more
promising; nearness alone does not make it turn back). A frontier counts as the one chosen while a frontier lies within ``keep_within_m`` of
where the chosen one was: frontiers move as the map grows around them.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np


class ChoiceRule(StrEnum):
    SAMPLE = "sample"  # the paper's: a fresh draw ∝ w_p every step (FBE: the nearest every step)
    COMMITTED = "committed"  # a draw ∝ w_p·exp(−λ·d_p), then kept until reached, gone or clearly beaten


@dataclass(frozen=True)
class FrontierChoiceConfig:
    """How the next frontier is chosen from the weighted candidates."""

    rule: str = ChoiceRule.COMMITTED
    distance_cost_per_m: float = 0.25  # λ: a frontier 4 m farther needs e times the weight
    keep_within_m: float = 1.0
    switch_margin: float = 1.5  # in log weight: a frontier e^1.5 ≈ 4.5 times as good takes over

    def __post_init__(self) -> None:
        if self.rule not in set(ChoiceRule):
            raise ValueError(f"frontier_choice.rule: {self.rule!r} is not one of {', '.join(ChoiceRule)}")
        for name in ("distance_cost_per_m", "keep_within_m", "switch_margin"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value >= 0):
                raise ValueError(f"frontier_choice.{name}: {value!r} must be a finite number >= 0")


def choose_frontier(centres_xy: np.ndarray, distances_m: np.ndarray, log_weights: np.ndarray | None,
                    goal_xy: np.ndarray | None, config: FrontierChoiceConfig,
                    rng: np.random.Generator) -> int | None:
    """The index of the frontier to head for, or None when there is none.

    Args:
        centres_xy: (K, 2) world positions of the candidate frontiers' centres.
        distances_m: (K,) path lengths from the robot to them.
        log_weights: (K,) log w_p of the semantic methods; None for FBE (no weights: the nearest).
        goal_xy: where the frontier chosen at an earlier step was, or None.
        config: the rule and its constants.
        rng: the episode's seeded generator, for the draws.

    Returns:
        An index into the candidates.
    """
    count = len(distances_m)
    if count == 0:
        return None
    distances = np.asarray(distances_m, dtype=float)
    if config.rule == ChoiceRule.SAMPLE:
        return _fresh(distances, log_weights, 0.0, rng)
    weights = np.zeros(count) if log_weights is None else np.asarray(log_weights, dtype=float)
    kept = kept_goal(centres_xy, goal_xy, config.keep_within_m)
    if kept is not None and weights.max() - weights[kept] < config.switch_margin:
        return kept
    return _fresh(distances, log_weights, config.distance_cost_per_m, rng)


def kept_goal(centres_xy: np.ndarray, goal_xy: np.ndarray | None, keep_within_m: float) -> int | None:
    """The candidate that is the earlier goal (the nearest to it, if within ``keep_within_m``), else
    None: frontiers move as the map grows, so the goal is found again by place, not by identity.

    Args:
        centres_xy: the candidates' centres (N, 2).
        goal_xy: the earlier goal, or None.
        keep_within_m: how far a frontier may have moved and still be the goal.

    Returns:
        The candidate's index, or None.
    """
    if goal_xy is None or len(centres_xy) == 0:
        return None
    gaps = np.hypot(*(np.asarray(centres_xy, dtype=float) - np.asarray(goal_xy, dtype=float)[None, :]).T)
    nearest = int(np.argmin(gaps))
    return nearest if gaps[nearest] <= keep_within_m else None


def _fresh(distances: np.ndarray, log_weights: np.ndarray | None, distance_cost: float,
           rng: np.random.Generator) -> int:
    """FBE: the nearest; the semantic methods: a draw ∝ exp(log w − λ·d)."""
    if log_weights is None:
        return int(np.argmin(distances))
    return sample_frontier(np.asarray(log_weights, dtype=float) - distance_cost * distances, rng)


def frontier_probabilities(log_weights: np.ndarray) -> np.ndarray:
    """w / Σw computed from exponents, with the largest subtracted first so nothing overflows.

    Args:
        log_weights: log w per frontier.

    Returns:
        The probabilities.
    """
    log_weights = np.asarray(log_weights, dtype=float)
    shifted = np.exp(log_weights - log_weights.max())
    return shifted / shifted.sum()


def sample_frontier(log_weights: np.ndarray, rng: np.random.Generator) -> int:
    """An index drawn ∝ exp(log_weights); raises ValueError when there is nothing to draw.

    Args:
        log_weights: log w per frontier.
        rng: the draw's generator.

    Returns:
        The frontier's index.

    Raises:
        ValueError: no frontier.
    """
    if len(log_weights) == 0:
        raise ValueError("no frontier to sample")
    probabilities = frontier_probabilities(log_weights)
    return int(rng.choice(len(probabilities), p=probabilities))
