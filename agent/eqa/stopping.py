"""When to stop exploring and which answer to give: conformal prediction and its baselines.

Every rule sees the episode's scores one step at a time and either lets the robot go on or returns
a `StopDecision`. The same rule objects run inside the tree (behaviours.confidence) and over the
recorded scores of full-budget episodes (agent.app.eval.stop), so an evaluation measures exactly what a
robot would have done.

- ``cp``: the running conformal prediction set; stop when one answer is left, which is the answer.
  An empty set means no answer fits, so the robot stops and falls back.
- ``entropy``: stop when H(f̂) (in nats; at most ln 4 ≈ 1.386 for four letters) is below the
  threshold, answering argmax f̂ of that step.
- ``relevance``: stop when Rel is above the threshold, answering argmax f̂ of that step.
- ``budget``: never stop early.

Whenever a rule reaches the budget without deciding, the answer is argmax f̂ at the step of
highest Rel (`fallback_decision`).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Protocol

from agent.eqa.answers import AnswerLog, StepScores
from agent.eqa.conformal import PredictionSet


class StopRuleName(StrEnum):
    CP = "cp"
    ENTROPY = "entropy"
    RELEVANCE = "relevance"
    BUDGET = "budget"


@dataclass(frozen=True)
class StopConfig:
    """Which stopping rule the robot uses, and its parameter.

    ``epsilon`` is the miscoverage the user accepts: the conformal set holds the true answer with
    probability at least 1 − ε. ``calibration`` is a file from ``homebot calibrate``; empty means
    the calibration shipped with homebot for the default policy and simulated VLM.
    """

    rule: str = StopRuleName.CP
    epsilon: float = 0.3
    calibration: str = ""
    entropy_threshold: float = 0.1
    relevance_threshold: float = 0.5
    accept_mismatched_calibration: bool = False

    def __post_init__(self) -> None:
        if self.rule not in set(StopRuleName):
            raise ValueError(f"stop.rule: {self.rule!r} is not one of {', '.join(StopRuleName)}")
        if not 0 < self.epsilon < 1:
            raise ValueError(f"stop.epsilon: {self.epsilon!r} is not in the open interval (0, 1)")
        if not (math.isfinite(self.entropy_threshold) and self.entropy_threshold > 0):
            raise ValueError(f"stop.entropy_threshold: {self.entropy_threshold!r} must be a number above 0")
        if not 0 <= self.relevance_threshold <= 1:
            raise ValueError(f"stop.relevance_threshold: {self.relevance_threshold!r} is not in [0, 1]")


@dataclass(frozen=True)
class StopDecision:
    """The robot stops after ``step`` steps and answers ``letter``, read from step ``from_step``."""

    step: int
    letter: str
    from_step: int
    reason: str


def entropy(probs: Iterable[float]) -> float:
    """Shannon entropy in nats; zero probabilities add nothing.

    Args:
        probs: a distribution's probabilities.

    Returns:
        The entropy.
    """
    return -sum(p * math.log(p) for p in probs if p > 0)


def fallback_decision(log: AnswerLog, reason: str) -> StopDecision:
    """Argmax f̂ at the step of highest Rel: the answer when no rule decided earlier.

    Args:
        log: the episode's scored steps (at least one).
        reason: why no rule decided (the start of the decision's reason).

    Returns:
        The decision.
    """
    best = log.fallback()
    return StopDecision(len(log), best.best(), best.step, f"{reason}: argmax f̂ at the most relevant step")


class StoppingRule(Protocol):
    name: str

    def observe(self, log: AnswerLog) -> StopDecision | None:
        """Look at the newest step of ``log``; a decision stops the robot.

        Args:
            log: the episode's scored steps so far.

        Returns:
            The decision to stop, or None to go on.
        """

    def describe(self) -> str:
        """One line for the tree's feedback: where the rule stands.

        Returns:
            The line.
        """


class BudgetRule:
    """Never stops early: the robot explores to its budget."""

    name = StopRuleName.BUDGET

    def observe(self, log: AnswerLog) -> StopDecision | None:
        return None

    def describe(self) -> str:
        return "explores to the budget"


class EntropyRule:
    """Stops when the newest answer distribution is sharp (low entropy).

    Args:
        threshold: the entropy (nats) below which it stops.
    """

    name = StopRuleName.ENTROPY

    def __init__(self, threshold: float) -> None:
        self.threshold = threshold
        self.last: float | None = None

    def observe(self, log: AnswerLog) -> StopDecision | None:
        step = log.steps[-1]
        self.last = entropy(step.answer_probs.values())
        if self.last < self.threshold:
            return StopDecision(step.step, step.best(), step.step, f"entropy {self.last:.3f} < {self.threshold:g}")
        return None

    def describe(self) -> str:
        return f"H(f̂) {self.last:.3f}, stop below {self.threshold:g}" if self.last is not None else "no step yet"


class RelevanceRule:
    """Stops when the VLM says it is confident about the view (Rel above the threshold).

    Args:
        threshold: the relevance above which it stops.
    """

    name = StopRuleName.RELEVANCE

    def __init__(self, threshold: float) -> None:
        self.threshold = threshold
        self.last: float | None = None

    def observe(self, log: AnswerLog) -> StopDecision | None:
        step = log.steps[-1]
        self.last = step.relevance
        if self.last > self.threshold:
            return StopDecision(step.step, step.best(), step.step, f"Rel {self.last:.3f} > {self.threshold:g}")
        return None

    def describe(self) -> str:
        return f"Rel {self.last:.3f}, stop above {self.threshold:g}" if self.last is not None else "no step yet"


class ConformalRule:
    """Keeps the running conformal prediction set and stops when it holds one answer (or none).

    Args:
        q_hat: q̂ from calibration.
        epsilon: ε, the error rate it was calibrated for.
        letters: the answer letters.
    """

    name = StopRuleName.CP

    def __init__(self, q_hat: float, epsilon: float, letters: Sequence[str]) -> None:
        self.epsilon = epsilon
        self.prediction_set = PredictionSet(q_hat, letters)

    @property
    def q_hat(self) -> float:
        return self.prediction_set.q_hat

    def observe(self, log: AnswerLog) -> StopDecision | None:
        step = log.steps[-1]
        left = self.prediction_set.update(step)
        if len(left) == 1:
            (letter,) = left
            return StopDecision(step.step, letter, step.step, f"conformal set is {{{letter}}} (ε {self.epsilon:g})")
        if not left:
            return fallback_decision(log, f"conformal set became empty at step {step.step}")
        return None

    def describe(self) -> str:
        return f"set {{{', '.join(self.prediction_set.sorted())}}}, q̂ {self.q_hat:.3f}, ε {self.epsilon:g}"


def replay(rule: StoppingRule, steps: Sequence[StepScores], budget: int) -> StopDecision:
    """What ``rule`` would have done over an episode's recorded steps (at most ``budget`` of them).

    Args:
        rule: a fresh rule.
        steps: the recorded steps, in order.
        budget: the most steps the robot could take.

    Returns:
        The rule's decision, or the fallback decision at the budget.
    """
    log = AnswerLog()
    for step in steps[:budget]:
        log.add(step.answer_probs, step.relevance)
        decision = rule.observe(log)
        if decision is not None:
            return decision
    return fallback_decision(log, "budget spent" if len(log) >= budget else "nothing left to explore")


def make_rule(stop: StopConfig, q_hat: float | None, letters: Sequence[str]) -> StoppingRule:
    """The rule ``stop.rule`` names; the conformal rule needs q̂ from a calibration file.

    Args:
        stop: the stopping settings.
        q_hat: q̂ from a calibration file, or None.
        letters: the question's answer letters.

    Returns:
        The rule.

    Raises:
        ValueError: the conformal rule without q̂.
    """
    if stop.rule == StopRuleName.CP:
        if q_hat is None:
            raise ValueError("stop.rule cp needs q̂ from a calibration file")
        return ConformalRule(q_hat, stop.epsilon, letters)
    if stop.rule == StopRuleName.ENTROPY:
        return EntropyRule(stop.entropy_threshold)
    if stop.rule == StopRuleName.RELEVANCE:
        return RelevanceRule(stop.relevance_threshold)
    return BudgetRule()
