"""Multi-step conformal prediction: q̂ against puncc, Claim 1 (running set = sequence set), coverage."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from deel.puncc.api.calibration import BaseCalibrator

from agent.eqa.answers import StepScores
from agent.eqa.conformal import (
    PredictionSet,
    conformal_quantile,
    conformal_rank,
    conformity_scores,
    exact_fraction,
    nonconformity,
    sequence_set,
    step_set,
)

LETTERS = ("A", "B", "C", "D")


def puncc_quantile(scores: np.ndarray, epsilon: float) -> float:
    """q̂ as puncc computes it: the (1−α) quantile of the scores with +∞ appended (inverted CDF)."""
    calibrator = BaseCalibrator(
        nonconf_score_func=lambda y_pred, y_true: y_pred,
        pred_set_func=lambda y_pred, scores_quantile: (y_pred, y_pred),
    )
    calibrator.fit(y_true=scores, y_pred=scores)
    return float(calibrator.compute_quantile(alpha=epsilon))


def exact_product(n: int, epsilon: float) -> Fraction:
    return (n + 1) * (1 - Fraction(repr(epsilon)))


# ---------------------------------------------------------------------------------------------
# q̂


def test_quantile_agrees_with_puncc_away_from_integer_boundaries() -> None:
    rng = np.random.default_rng(20240611)
    grid = [round(e, 3) for e in np.arange(0.005, 1.0, 0.005)]  # 0.005 … 0.995
    compared = boundary = refused = 0
    for n in range(1, 401):
        scores = rng.uniform(1.0, 2.0, size=n)  # κ lies in [1, 2]
        epsilons = set(rng.choice(grid, size=8, replace=False).tolist()) | {0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 0.9}
        sorted_scores = sorted(scores.tolist())
        for eps in sorted(epsilons):
            ours = conformal_quantile(scores.tolist(), eps)
            product = exact_product(n, eps)
            if product.denominator == 1:
                # Float and exact arithmetic may disagree here: check against the exact rank.
                boundary += 1
                k = int(product)
                expected = math.inf if k > n else sorted_scores[k - 1]
                assert ours == expected, (n, eps)
                continue
            try:
                theirs = puncc_quantile(scores, eps)
            except ValueError:
                refused += 1  # puncc refuses ε < 1/(N+1)…
                assert ours == math.inf, (n, eps)  # …exactly where too few scores give +∞ for us
                continue
            assert math.isfinite(ours), (n, eps)
            compared += 1
            assert ours == theirs, (n, eps, ours, theirs)
    # the comparison actually exercised every branch
    assert compared > 4000 and boundary > 100 and refused > 10


def test_boundary_rank_is_exact_where_floating_point_is_not() -> None:
    assert math.ceil(10 * (1 - 0.7)) == 4  # what float arithmetic would pick
    assert conformal_rank(9, 0.7) == 3
    kappas = [1.9, 1.1, 1.5, 1.3, 1.7, 1.2, 1.8, 1.4, 1.6]
    assert conformal_quantile(kappas, 0.7) == 1.3  # third smallest, not fourth (1.4)
    assert conformal_rank(9, Fraction(7, 10)) == 3
    assert conformal_rank(19, 0.05) == 19  # 20 · 0.95 = 19 exactly


def test_too_few_scores_give_infinity() -> None:
    assert conformal_rank(5, 0.1) == 6  # ⌈6 · 0.9⌉ = ⌈5.4⌉
    assert conformal_quantile([1.1, 1.2, 1.3, 1.4, 1.5], 0.1) == math.inf
    assert conformal_quantile([1.5], 0.3) == math.inf  # ⌈2 · 0.7⌉ = 2 > 1
    assert conformal_quantile([1.5], 0.5) == 1.5  # ⌈2 · 0.5⌉ = 1
    # the largest score, not +∞, at the smallest ε that N can support
    assert conformal_quantile([1.0 + i / 10 for i in range(9)], Fraction(1, 10)) == 1.8


def test_quantile_ignores_input_order_and_rejects_bad_input() -> None:
    kappas = [1.4, 1.1, 1.9, 1.2, 1.3]
    assert conformal_quantile(kappas, 0.5) == conformal_quantile(sorted(kappas), 0.5) == 1.3
    with pytest.raises(ValueError):
        conformal_quantile([], 0.3)
    for bad in (0.0, 1.0, -0.1, 1.5):
        with pytest.raises(ValueError, match="epsilon"):
            conformal_rank(10, bad)


def test_exact_fraction_reads_the_decimal_written() -> None:
    assert exact_fraction(0.3) == Fraction(3, 10)
    assert exact_fraction(0.7) == Fraction(7, 10)
    assert exact_fraction(Fraction(1, 3)) == Fraction(1, 3)
    assert exact_fraction(np.float64(0.25)) == Fraction(1, 4)


# ---------------------------------------------------------------------------------------------
# scores and sets


def test_conformity_and_nonconformity_by_hand() -> None:
    step = StepScores(1, {"A": 0.7, "B": 0.2, "C": 0.1, "D": 0.0}, 0.5)
    rho = conformity_scores(step)
    assert rho == pytest.approx({"A": -0.15, "B": -0.4, "C": -0.45, "D": -0.5})
    irrelevant = StepScores(2, {"A": 0.0, "B": 0.0, "C": 0.0, "D": 1.0}, 0.0)
    assert all(v == 0 for v in conformity_scores(irrelevant).values())  # rules nothing out
    sharp = StepScores(3, {"A": 0.1, "B": 0.8, "C": 0.05, "D": 0.05}, 1.0)
    # κ = 1 − min over steps of ρ_truth
    assert nonconformity([step, irrelevant, sharp], "A") == pytest.approx(1 + 0.9)
    assert nonconformity([step, irrelevant, sharp], "B") == pytest.approx(1 + 0.4)
    with pytest.raises(ValueError):
        nonconformity([], "A")
    # with q̂ = 1.5 the threshold is −0.5: A (min −0.9) is out, B (min −0.4) stays
    assert sequence_set([step, irrelevant, sharp], 1.5) == {"B"}
    assert step_set(rho, -0.42) == {"A", "B"}


def random_step(rng: np.random.Generator, step: int) -> StepScores:
    probs = rng.dirichlet(np.full(len(LETTERS), 0.7))
    return StepScores(step, dict(zip(LETTERS, probs.tolist())), float(rng.uniform(0.0, 1.0)))


def test_running_set_ends_as_the_sequence_set_claim_1() -> None:
    rng = np.random.default_rng(1)
    sizes = set()
    for _ in range(2000):
        steps = [random_step(rng, t + 1) for t in range(int(rng.integers(1, 12)))]
        q_hat = float(rng.uniform(1.0, 2.0)) if rng.random() < 0.9 else float(rng.choice([math.inf, 1.0, 2.0]))
        final = sequence_set(steps, q_hat)
        running = PredictionSet(q_hat, LETTERS)
        previous = set(LETTERS)
        for step in steps:
            now = running.update(step)
            assert final <= now, (steps, q_hat)
            assert now <= previous  # an answer once excluded never comes back
            previous = now
        assert running.members == final
        assert running.sorted() == sorted(final)
        sizes.add(len(final))
    assert sizes == {0, 1, 2, 3, 4}  # the random cases reach every set size


def test_infinite_quantile_excludes_nothing() -> None:
    rng = np.random.default_rng(3)
    steps = [random_step(rng, t + 1) for t in range(8)]
    running = PredictionSet(math.inf, LETTERS)
    assert running.threshold == -math.inf
    for step in steps:
        assert running.update(step) == set(LETTERS)
    assert sequence_set(steps, math.inf) == set(LETTERS)


# ---------------------------------------------------------------------------------------------
# coverage on exchangeable synthetic episodes


def synthetic_episodes(rng: np.random.Generator, count: int) -> list[tuple[list[StepScores], str]]:
    """Episodes with a random truth, whose VLM is informative in proportion to the view's relevance."""
    episodes = []
    for _ in range(count):
        truth = int(rng.integers(len(LETTERS)))
        length = int(rng.integers(3, 9))
        relevance = rng.uniform(0.0, 1.0, size=length)
        concentration = np.ones((length, len(LETTERS)))
        concentration[:, truth] += 4.0 * relevance
        draws = rng.gamma(concentration)  # one Dirichlet draw per row
        probs = (draws / draws.sum(axis=1, keepdims=True)).tolist()
        steps = [StepScores(t + 1, dict(zip(LETTERS, probs[t])), float(relevance[t])) for t in range(length)]
        episodes.append((steps, LETTERS[truth]))
    return episodes


EPSILONS = (0.1, 0.2, 0.3)


def test_sequence_set_covers_the_truth_at_rate_one_minus_epsilon() -> None:
    rng = np.random.default_rng(2024)
    # A small calibration set makes each order statistic a 1/(N+1) = 5 % step in coverage, so
    # picking the wrong one shows; many repeats average out each calibration's own luck.
    n_calib, n_test, repeats = 19, 20, 200
    covered = dict.fromkeys(EPSILONS, 0)
    singletons = dict.fromkeys(EPSILONS, 0)
    total = 0
    for _ in range(repeats):  # fresh calibration and test episodes each time, all drawn alike
        kappas = [nonconformity(steps, truth) for steps, truth in synthetic_episodes(rng, n_calib)]
        q_hats = {eps: conformal_quantile(kappas, eps) for eps in EPSILONS}
        assert all(math.isfinite(q) for q in q_hats.values())
        for steps, truth in synthetic_episodes(rng, n_test):
            total += 1
            for eps, q_hat in q_hats.items():
                found = sequence_set(steps, q_hat)
                covered[eps] += truth in found
                singletons[eps] += len(found) == 1
    for eps in EPSILONS:
        coverage = covered[eps] / total
        # binomial error of the test draws, plus the spread of each calibration's own coverage
        # (Beta-distributed, variance ≈ ε(1−ε)/(N+2)) averaged over the repeats
        se = math.sqrt(eps * (1 - eps) / total + eps * (1 - eps) / ((n_calib + 2) * repeats))
        assert coverage >= 1 - eps - 3 * se, (eps, coverage)
        # without ties, coverage is at most 1 − ε + 1/(N+1): the set is not trivially everything
        assert coverage <= 1 - eps + 1 / (n_calib + 1) + 3 * se, (eps, coverage)
        assert coverage < 0.95
        assert singletons[eps] > 0
