"""Multi-step conformal prediction (Explore until Confident, §V-B and Appendix A).

A step's score for answer y is ρ_y^t = Rel(x_t)·(f̂_y(x_t) − 1), in [−1, 0]: a view the VLM finds
irrelevant (Rel ≈ 0) scores every answer near 0 and so rules nothing out. An episode's score is
the minimum over its steps, and its non-conformity is κ = 1 − min_t ρ_{y_true}^t. Calibration keeps
the N calibration episodes' κ; q̂(ε) is their k-th smallest with k = ⌈(N+1)(1−ε)⌉, and at test time
the robot keeps the running intersection of C^t = {y : ρ_y^t ≥ 1 − q̂}, which (Claim 1) ends as
the sequence-level set {y : min_t ρ_y^t ≥ 1 − q̂} that covers the truth with probability ≥ 1 − ε.

Everything here works on plain numbers, so it is tested without a robot.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from fractions import Fraction

from agent.eqa.answers import StepScores


def exact_fraction(epsilon: float | Fraction) -> Fraction:
    """ε as the decimal the user wrote: 0.3 is 3/10, not the binary double just below it.

    Args:
        epsilon: ε, as a float or an exact fraction.

    Returns:
        ε as a fraction.

    Raises:
        ValueError: ε is not in (0, 1).
    """
    value = epsilon if isinstance(epsilon, Fraction) else Fraction(repr(float(epsilon)))
    if not 0 < value < 1:
        raise ValueError(f"epsilon: {float(epsilon)!r} is not in the open interval (0, 1)")
    return value


def conformal_rank(n: int, epsilon: float | Fraction) -> int:
    """k = ⌈(N+1)(1−ε)⌉, computed exactly; k > N means the quantile is +∞.

    Floating point gets this wrong at the boundaries (``10 * (1 - 0.7)`` is 3.0000000000000004,
    whose ceiling is 4), which would quietly pick the next order statistic.

    Args:
        n: N, the number of calibration scores.
        epsilon: ε, the error rate promised.

    Returns:
        k.

    Raises:
        ValueError: no calibration score, or ε not in (0, 1).
    """
    if n < 1:
        raise ValueError("conformal prediction needs at least one calibration score")
    return math.ceil((n + 1) * (1 - exact_fraction(epsilon)))


def conformal_quantile(kappas: Sequence[float], epsilon: float | Fraction) -> float:
    """q̂(ε): the k-th smallest non-conformity score, or +∞ when there are too few to promise 1 − ε.

    Args:
        kappas: the calibration's non-conformity scores κ.
        epsilon: ε, the error rate promised.

    Returns:
        q̂(ε).
    """
    k = conformal_rank(len(kappas), epsilon)
    if k > len(kappas):
        return math.inf
    return float(sorted(kappas)[k - 1])


def conformity_scores(step: StepScores) -> dict[str, float]:
    """ρ_y^t = Rel·(f̂_y − 1) for every answer letter of one step.

    Args:
        step: the step's answer probabilities and relevance.

    Returns:
        ρ per answer letter.
    """
    return {letter: step.relevance * (p - 1.0) for letter, p in step.answer_probs.items()}


def nonconformity(steps: Iterable[StepScores], truth: str) -> float:
    """κ = 1 − min_t ρ_truth^t over an episode run to its full budget.

    Args:
        steps: the episode's steps.
        truth: the correct answer's letter.

    Returns:
        κ.

    Raises:
        ValueError: no step was scored.
    """
    rhos = [conformity_scores(step)[truth] for step in steps]
    if not rhos:
        raise ValueError("an episode with no scored step has no non-conformity score")
    return 1.0 - min(rhos)


def sequence_set(steps: Iterable[StepScores], q_hat: float) -> set[str]:
    """The sequence-level set {y : min_t ρ_y^t ≥ 1 − q̂} of a whole episode.

    Args:
        steps: the episode's steps.
        q_hat: q̂ from calibration.

    Returns:
        The letters in the set.
    """
    minimum: dict[str, float] = {}
    for step in steps:
        for letter, rho in conformity_scores(step).items():
            minimum[letter] = min(rho, minimum.get(letter, 0.0))
    return {letter for letter, rho in minimum.items() if rho >= 1.0 - q_hat}


class PredictionSet:
    """The running intersection ∩_{k≤t} C^k, updated one step at a time.

    Before the first step every answer is possible; an answer once excluded never comes back,
    which is why a single remaining answer can be given at once.

    Args:
        q_hat: q̂ from calibration.
        letters: the answer letters.
    """

    def __init__(self, q_hat: float, letters: Sequence[str]) -> None:
        self.q_hat = q_hat
        self.members: set[str] = set(letters)

    @property
    def threshold(self) -> float:
        """An answer stays while ρ_y^t ≥ 1 − q̂ (−∞ when q̂ is +∞: nothing is ever excluded)."""
        return 1.0 - self.q_hat

    def update(self, step: StepScores) -> set[str]:
        self.members &= step_set(conformity_scores(step), self.threshold)
        return set(self.members)

    def sorted(self) -> list[str]:
        """The answers still in the set, in letter order.

        Returns:
            The letters.
        """
        return sorted(self.members)


def step_set(rhos: Mapping[str, float], threshold: float) -> set[str]:
    """C^t: the answers whose score this step is at least the threshold 1 − q̂.

    Args:
        rhos: ρ per answer letter at this step.
        threshold: 1 − q̂.

    Returns:
        The letters in C^t.
    """
    return {letter for letter, rho in rhos.items() if rho >= threshold}
