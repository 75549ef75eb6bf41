"""The simulated VLM's measured properties (docs/vlm-sim.md) at its default parameters, on frames
rendered in PyBullet from 24 generated homes: three questions a home, each shown from where its
answer shows and from as many spots anywhere (`agent.app.eval.vlm_cases`)."""

from __future__ import annotations

import math

import pytest

from agent.app.eval.vlm_cases import home_cases
from agent.vlm.measure import Case, Report, measure, roc_auc, room_judgement
from agent.vlm.sim import SimParams, SimulatedVLM

HOMES = range(24)


@pytest.fixture(scope="module")
def cases() -> list[Case]:
    return home_cases(HOMES)


@pytest.fixture(scope="module")
def report(cases: list[Case]) -> Report:
    return measure(SimulatedVLM(), cases)


def test_the_evaluation_has_views_of_every_sort(report: Report) -> None:
    assert report.cases >= 300 and report.in_view >= 40 and report.irrelevant >= 100


def test_with_the_target_in_clear_view_the_answer_is_right(report: Report) -> None:
    assert report.accuracy_in_view >= 0.8


def test_with_nothing_relevant_in_view_answers_are_confident_and_biased(report: Report) -> None:
    """The Entropy rule's failure: low entropy, far from uniform, the same favourite whatever the
    view, and right no more often than a guess."""
    assert report.entropy_irrelevant <= 0.6
    assert report.same_answer_irrelevant >= 0.8
    assert report.accuracy_irrelevant <= 0.5


def test_relevance_tells_right_answers_from_wrong_ones(report: Report) -> None:
    assert report.relevance_auc >= 0.75


def test_rooms_are_misjudged_about_as_often_as_documented(cases: list[Case]) -> None:
    """Reading rooms off furniture goes wrong on its own now and then (a bench read as a hallway's
    in a garage); ``room_error`` adds misjudgements on top."""
    default = room_judgement(SimulatedVLM(), cases)
    exact = room_judgement(SimulatedVLM(SimParams(room_error=0.0)), cases)
    assert default.judged >= 200 and default.judged / default.floors >= 0.3
    assert exact.error <= 0.08
    assert 0.05 <= default.error - exact.error <= 0.15


def test_auc_counts_ties_half_and_needs_both_kinds() -> None:
    assert roc_auc([0.9, 0.5, 0.5, 0.1], [True, True, False, False]) == pytest.approx(0.875)
    assert math.isnan(roc_auc([0.3, 0.4], [True, True]))
