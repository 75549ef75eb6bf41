"""The confidence leaves on a plain blackboard: the rule decides, the tree stops and answers."""

from __future__ import annotations

from collections.abc import Iterator

import py_trees
import pytest
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from agent.eqa.answers import AnswerLog
from agent.eqa.stopping import BudgetRule, ConformalRule, RelevanceRule
from behaviours.answer import Answer, AnswerFallback
from behaviours.confidence import CheckConfidence, UpdatePredictionSet
from behaviours.select_frontier import MarkExplorationComplete

CHOICES = ["kitchen", "bedroom", "garage", "office"]


@pytest.fixture(autouse=True)
def blackboard() -> Iterator[py_trees.blackboard.Client]:
    py_trees.blackboard.Blackboard.clear()
    client = py_trees.blackboard.Client(name="test")
    for key, value in ((bb.ANSWER_LOG, AnswerLog()), (bb.CHOICES, CHOICES), (bb.EXPLORATION_COMPLETE, False),
                       (bb.PLAN, None)):
        client.register_key(key, access=Access.WRITE)
        client.set(key, value)
    client.register_key(bb.ANSWER, access=Access.READ)
    yield client
    py_trees.blackboard.Blackboard.clear()


def _tree(rule) -> tuple[py_trees.behaviour.Behaviour, UpdatePredictionSet]:
    update = UpdatePredictionSet(rule)
    confident = py_trees.composites.Sequence("Confident", memory=False, children=[CheckConfidence(), Answer()])
    root = py_trees.composites.Selector("root", memory=False, children=[confident, update])
    return root, update


def _step(client, probs: dict[str, float], relevance: float) -> None:
    client.get(bb.ANSWER_LOG).add(probs, relevance)


def test_the_conformal_set_narrows_then_the_single_answer_is_given(blackboard) -> None:
    root, _ = _tree(ConformalRule(1.5, 0.3, "ABCD"))
    _step(blackboard, {"A": 0.25, "B": 0.25, "C": 0.25, "D": 0.25}, 0.1)  # irrelevant: rules nothing out
    root.tick_once()
    assert py_trees.blackboard.Blackboard.get(bb.STOP_DECISION) is None
    assert py_trees.blackboard.Blackboard.get(bb.PREDICTION_SET) == ["A", "B", "C", "D"]
    assert py_trees.blackboard.Blackboard.get(bb.Q_HAT) == 1.5
    _step(blackboard, {"A": 0.05, "B": 0.85, "C": 0.05, "D": 0.05}, 0.9)  # B keeps -0.135, others -0.855
    root.tick_once()
    assert py_trees.blackboard.Blackboard.get(bb.PREDICTION_SET) == ["B"]
    root.tick_once()  # the next tick answers
    answer = blackboard.get(bb.ANSWER)
    assert answer["letter"] == "B" and answer["text"] == "bedroom"
    assert answer["stopped_after"] == 2 and answer["rule"].startswith("conformal set is {B}")


def test_a_step_is_shown_to_the_rule_once_however_often_the_leaf_ticks(blackboard) -> None:
    update = UpdatePredictionSet(RelevanceRule(0.5))
    _step(blackboard, {"A": 0.7, "B": 0.1, "C": 0.1, "D": 0.1}, 0.2)
    for _ in range(3):
        update.tick_once()
    assert update.seen_steps == 1
    assert py_trees.blackboard.Blackboard.get(bb.STOP_DECISION) is None
    assert py_trees.blackboard.Blackboard.get(bb.PREDICTION_SET) is None  # only the cp rule has a set


def test_the_budget_rule_never_makes_check_confidence_succeed(blackboard) -> None:
    update, check = UpdatePredictionSet(BudgetRule()), CheckConfidence()
    for relevance in (0.99, 1.0):
        _step(blackboard, {"A": 1.0, "B": 0.0, "C": 0.0, "D": 0.0}, relevance)
        update.tick_once()
        check.tick_once()
        assert check.status == Status.FAILURE


def test_answer_fallback_takes_the_most_relevant_step(blackboard) -> None:
    _step(blackboard, {"A": 0.7, "B": 0.1, "C": 0.1, "D": 0.1}, 0.2)
    _step(blackboard, {"A": 0.1, "B": 0.1, "C": 0.7, "D": 0.1}, 0.8)
    _step(blackboard, {"A": 0.1, "B": 0.7, "C": 0.1, "D": 0.1}, 0.5)
    fallback = AnswerFallback()
    fallback.tick_once()
    answer = blackboard.get(bb.ANSWER)
    assert (answer["letter"], answer["from_step"], answer["stopped_after"]) == ("C", 2, 3)
    assert answer["rule"].startswith("budget spent")


def test_nothing_left_to_explore_only_when_no_frontier_was_planned(blackboard) -> None:
    mark = MarkExplorationComplete()
    blackboard.set(bb.PLAN, object())  # a frontier was planned: the move decides, not this leaf
    mark.tick_once()
    assert mark.status == Status.FAILURE and blackboard.get(bb.EXPLORATION_COMPLETE) is False
    blackboard.set(bb.PLAN, None)
    mark.tick_once()
    assert mark.status == Status.SUCCESS and blackboard.get(bb.EXPLORATION_COMPLETE) is True
