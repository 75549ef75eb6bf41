"""Stopping rules on hand-made score sequences, their configuration, and replay over recorded steps."""

from __future__ import annotations

import math

import pytest

from agent.app.config import ConfigError, load_config
from agent.eqa.answers import AnswerLog, StepScores
from agent.eqa.stopping import (
    BudgetRule,
    ConformalRule,
    EntropyRule,
    RelevanceRule,
    StopConfig,
    StopDecision,
    StopRuleName,
    entropy,
    fallback_decision,
    make_rule,
    replay,
)

LETTERS = ("A", "B", "C", "D")


def steps_of(*rows: tuple[dict[str, float], float]) -> list[StepScores]:
    return [StepScores(i + 1, probs, rel) for i, (probs, rel) in enumerate(rows)]


def p(a: float, b: float, c: float, d: float) -> dict[str, float]:
    return {"A": a, "B": b, "C": c, "D": d}


# ---------------------------------------------------------------------------------------------
# configuration


@pytest.mark.parametrize(
    ("changes", "field"),
    [
        ({"rule": "confidence"}, "stop.rule"),
        ({"rule": ""}, "stop.rule"),
        ({"epsilon": 0.0}, "stop.epsilon"),
        ({"epsilon": 1.0}, "stop.epsilon"),
        ({"epsilon": -0.2}, "stop.epsilon"),
        ({"epsilon": math.nan}, "stop.epsilon"),
        ({"entropy_threshold": 0.0}, "stop.entropy_threshold"),
        ({"entropy_threshold": -1.0}, "stop.entropy_threshold"),
        ({"relevance_threshold": -0.01}, "stop.relevance_threshold"),
        ({"relevance_threshold": 1.01}, "stop.relevance_threshold"),
    ],
)
def test_stop_config_rejects_bad_values_naming_the_field(changes: dict, field: str) -> None:
    with pytest.raises(ValueError, match=field.replace(".", r"\.")):
        StopConfig(**changes)


def test_stop_config_accepts_every_rule_and_edge_thresholds() -> None:
    for rule in ("cp", "entropy", "relevance", "budget"):
        assert StopConfig(rule=rule).rule == rule
    assert StopConfig(relevance_threshold=0.0).relevance_threshold == 0.0
    assert StopConfig(relevance_threshold=1.0).relevance_threshold == 1.0
    assert StopConfig(epsilon=0.01, entropy_threshold=2.0).epsilon == 0.01


def test_bad_stop_values_from_the_command_line_are_config_errors() -> None:
    with pytest.raises(ConfigError, match=r"stop\.rule"):
        load_config(overrides=["stop.rule=sometimes"])
    with pytest.raises(ConfigError, match=r"stop\.epsilon"):
        load_config(overrides=["stop.epsilon=1.5"])
    config = load_config(overrides=["stop.rule=entropy", "stop.entropy_threshold=0.4"])
    assert (config.stop.rule, config.stop.entropy_threshold) == ("entropy", 0.4)


@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_stop_config_rejects_non_finite_entropy_threshold(value: float) -> None:
    # NaN would compare False with every entropy, so the entropy rule would never stop
    with pytest.raises(ValueError, match=r"stop\.entropy_threshold"):
        StopConfig(entropy_threshold=value)
    with pytest.raises(ConfigError, match=r"stop\.entropy_threshold"):
        load_config(overrides=[f"stop.entropy_threshold={'NaN' if math.isnan(value) else 'Infinity'}"])


def test_make_rule_builds_the_named_rule() -> None:
    assert isinstance(make_rule(StopConfig(rule="budget"), None, LETTERS), BudgetRule)
    entropy_rule = make_rule(StopConfig(rule="entropy", entropy_threshold=0.25), None, LETTERS)
    assert isinstance(entropy_rule, EntropyRule) and entropy_rule.threshold == 0.25
    relevance_rule = make_rule(StopConfig(rule="relevance", relevance_threshold=0.8), None, LETTERS)
    assert isinstance(relevance_rule, RelevanceRule) and relevance_rule.threshold == 0.8
    cp = make_rule(StopConfig(rule="cp", epsilon=0.2), 1.4, LETTERS)
    assert isinstance(cp, ConformalRule) and cp.q_hat == 1.4 and cp.epsilon == 0.2
    assert cp.prediction_set.members == set(LETTERS)
    with pytest.raises(ValueError, match="calibration"):
        make_rule(StopConfig(rule="cp"), None, LETTERS)
    assert {rule.name for rule in (entropy_rule, relevance_rule, cp)} == {"entropy", "relevance", "cp"}
    assert StopRuleName.BUDGET == "budget"


# ---------------------------------------------------------------------------------------------
# entropy


def test_entropy_is_in_nats() -> None:
    assert entropy([0.25] * 4) == pytest.approx(math.log(4))
    assert entropy([1.0, 0.0, 0.0, 0.0]) == 0.0
    assert entropy([0.5, 0.5, 0.0]) == pytest.approx(math.log(2))


def test_entropy_rule_stops_at_the_first_sharp_step_with_its_argmax() -> None:
    steps = steps_of(
        (p(0.25, 0.25, 0.25, 0.25), 0.9),  # H = ln 4 ≈ 1.386
        (p(0.7, 0.1, 0.1, 0.1), 0.9),  # H ≈ 0.940
        (p(0.05, 0.05, 0.85, 0.05), 0.1),  # H ≈ 0.588: first below 0.6
        (p(0.99, 0.0, 0.01, 0.0), 1.0),  # sharper still, but later
    )
    assert entropy(steps[2].answer_probs.values()) < 0.6 < entropy(steps[1].answer_probs.values())
    decision = replay(EntropyRule(0.6), steps, budget=10)
    assert (decision.step, decision.letter, decision.from_step) == (3, "C", 3)
    assert "entropy" in decision.reason
    # a lower threshold lets it go on to step 4
    later = replay(EntropyRule(0.1), steps, budget=10)
    assert (later.step, later.letter, later.from_step) == (4, "A", 4)
    # and one that no step reaches falls back to the most relevant step (step 4 here)
    assert replay(EntropyRule(0.01), steps, budget=10).reason.startswith("nothing left to explore")


def test_entropy_rule_describes_its_last_value() -> None:
    rule = EntropyRule(0.5)
    assert rule.describe() == "no step yet"
    log = AnswerLog()
    log.add(p(0.25, 0.25, 0.25, 0.25), 0.3)
    assert rule.observe(log) is None
    assert rule.describe().startswith("H(f̂) 1.386")


# ---------------------------------------------------------------------------------------------
# relevance


def test_relevance_rule_stops_at_the_first_relevant_step() -> None:
    steps = steps_of(
        (p(0.9, 0.05, 0.03, 0.02), 0.5),  # Rel equal to the threshold: not above
        (p(0.1, 0.6, 0.2, 0.1), 0.51),
        (p(0.0, 0.0, 0.0, 1.0), 0.99),
    )
    decision = replay(RelevanceRule(0.5), steps, budget=10)
    assert (decision.step, decision.letter, decision.from_step) == (2, "B", 2)
    assert "Rel" in decision.reason
    rule = RelevanceRule(0.5)
    assert rule.describe() == "no step yet"


# ---------------------------------------------------------------------------------------------
# budget and fallback


FALLBACK_STEPS = steps_of(
    (p(0.9, 0.05, 0.03, 0.02), 0.2),  # confident but irrelevant
    (p(0.1, 0.2, 0.6, 0.1), 0.8),  # the most relevant view: C
    (p(0.1, 0.7, 0.1, 0.1), 0.5),
    (p(0.0, 0.1, 0.1, 0.8), 0.8),  # ties on Rel with step 2, but later
)


def test_budget_rule_never_stops_early_and_falls_back_at_the_most_relevant_step() -> None:
    rule = BudgetRule()
    log = AnswerLog()
    for step in FALLBACK_STEPS:
        log.add(step.answer_probs, step.relevance)
        assert rule.observe(log) is None
    decision = replay(BudgetRule(), FALLBACK_STEPS, budget=4)
    assert (decision.step, decision.letter, decision.from_step) == (4, "C", 2)
    assert decision.reason.startswith("budget spent")


def test_fallback_decision_is_argmax_at_highest_relevance() -> None:
    log = AnswerLog()
    for step in FALLBACK_STEPS[:3]:
        log.add(step.answer_probs, step.relevance)
    decision = fallback_decision(log, "why")
    assert decision == StopDecision(3, "C", 2, "why: argmax f̂ at the most relevant step")


# ---------------------------------------------------------------------------------------------
# conformal


def test_conformal_rule_stops_with_the_singleton() -> None:
    # q̂ = 1.5: an answer stays while Rel·(f̂ − 1) ≥ −0.5
    steps = steps_of(
        (p(0.4, 0.3, 0.2, 0.1), 0.5),  # ρ = −0.3 −0.35 −0.4 −0.45: all stay
        (p(0.6, 0.3, 0.05, 0.05), 1.0),  # ρ = −0.4 −0.7 −0.95 −0.95: only A stays
        (p(0.0, 1.0, 0.0, 0.0), 1.0),  # would empty the set, but the robot has stopped
    )
    rule = ConformalRule(1.5, 0.3, LETTERS)
    decision = replay(rule, steps, budget=10)
    assert (decision.step, decision.letter, decision.from_step) == (2, "A", 2)
    assert "{A}" in decision.reason and "0.3" in decision.reason
    assert rule.prediction_set.members == {"A"}


def test_conformal_rule_narrows_step_by_step() -> None:
    rule = ConformalRule(1.5, 0.3, LETTERS)
    log = AnswerLog()
    log.add(p(0.4, 0.3, 0.2, 0.1), 0.5)
    assert rule.observe(log) is None
    assert rule.prediction_set.members == set(LETTERS)
    log.add(p(0.5, 0.45, 0.04, 0.01), 0.8)  # ρ = −0.4 −0.44 −0.768 −0.792: C, D out
    assert rule.observe(log) is None
    assert rule.describe() == "set {A, B}, q̂ 1.500, ε 0.3"
    log.add(p(0.01, 0.99, 0.0, 0.0), 0.1)  # irrelevant view: excludes nothing, C cannot come back
    assert rule.observe(log) is None
    log.add(p(0.2, 0.8, 0.0, 0.0), 1.0)  # ρ_A = −0.8: A out
    decision = rule.observe(log)
    assert decision is not None and (decision.step, decision.letter) == (4, "B")


def test_conformal_rule_empty_set_stops_with_the_fallback() -> None:
    # q̂ = 1.2: an answer stays while ρ ≥ −0.2
    steps = steps_of(
        (p(0.5, 0.5, 0.0, 0.0), 0.3),  # ρ = −0.15 −0.15 −0.3 −0.3: {A, B}
        (p(0.1, 0.2, 0.35, 0.35), 0.6),  # ρ_A = −0.54, ρ_B = −0.48: empty; most relevant so far
        (p(1.0, 0.0, 0.0, 0.0), 1.0),  # never reached
    )
    decision = replay(ConformalRule(1.2, 0.3, LETTERS), steps, budget=10)
    assert decision.step == 2
    assert decision.from_step == 2 and decision.letter in {"C", "D"}  # argmax f̂ at step 2 (a tie)
    assert "empty" in decision.reason
    # the fallback looks only at the steps so far: here the most relevant one is step 1
    steps = steps_of(
        (p(0.5, 0.5, 0.0, 0.0), 0.9),  # ρ = −0.45: with q̂ = 1.5 → {A, B}
        (p(0.0, 0.0, 0.9, 0.1), 0.6),  # ρ_A = ρ_B = −0.6: empty
    )
    decision = replay(ConformalRule(1.5, 0.3, LETTERS), steps, budget=10)
    assert (decision.step, decision.from_step) == (2, 1) and decision.letter in {"A", "B"}
    assert "empty" in decision.reason


def test_infinite_quantile_never_stops_early() -> None:
    steps = steps_of(*[(p(0.97, 0.01, 0.01, 0.01), 1.0)] * 3, (p(0.0, 0.0, 1.0, 0.0), 1.0))
    rule = ConformalRule(math.inf, 0.01, LETTERS)
    log = AnswerLog()
    for step in steps:
        log.add(step.answer_probs, step.relevance)
        assert rule.observe(log) is None
    assert rule.prediction_set.members == set(LETTERS)
    decision = replay(ConformalRule(math.inf, 0.01, LETTERS), steps, budget=4)
    assert (decision.step, decision.letter, decision.from_step) == (4, "A", 1)
    assert decision.reason.startswith("budget spent")


# ---------------------------------------------------------------------------------------------
# replay


def test_replay_ignores_steps_past_the_budget() -> None:
    steps = steps_of(
        (p(0.4, 0.3, 0.2, 0.1), 0.3),
        (p(0.1, 0.6, 0.2, 0.1), 0.4),
        (p(0.0, 0.0, 0.0, 1.0), 0.95),  # past the budget: would stop the relevance rule, and win the fallback
    )
    decision = replay(RelevanceRule(0.9), steps, budget=2)
    assert (decision.step, decision.letter, decision.from_step) == (2, "B", 2)
    assert decision.reason.startswith("budget spent")
    assert replay(BudgetRule(), steps, budget=2).letter == "B"
    assert replay(RelevanceRule(0.9), steps, budget=3).letter == "D"


def test_replay_says_nothing_left_when_the_episode_ended_early() -> None:
    steps = FALLBACK_STEPS[:3]
    decision = replay(BudgetRule(), steps, budget=10)
    assert (decision.step, decision.letter, decision.from_step) == (3, "C", 2)
    assert decision.reason.startswith("nothing left to explore")
    assert "budget spent" not in decision.reason
    exactly = replay(BudgetRule(), steps, budget=3)
    assert exactly.reason.startswith("budget spent")
