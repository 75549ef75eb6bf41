"""Stopping and answering: answer when the stopping rule decides, or from the best step at the end."""

from __future__ import annotations

from typing import Any

import py_trees
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from agent.eqa.answers import AnswerLog
from agent.eqa.stopping import StopDecision, fallback_decision
from worlds.bus.questions import LETTERS


class ShouldStop(py_trees.behaviour.Behaviour):
    """SUCCESS once the step budget is spent or no frontier is left; FAILURE while exploring.

    Args:
        name: the node's name.
    """

    def __init__(self, name: str = "ShouldStop") -> None:
        super().__init__(name)
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in (bb.BUDGET, bb.ANSWER_LOG, bb.EXPLORATION_COMPLETE):
            self.blackboard.register_key(key, access=Access.READ)

    def update(self) -> Status:
        steps, budget = len(self.blackboard.get(bb.ANSWER_LOG)), self.blackboard.get(bb.BUDGET)
        if steps >= budget:
            self.feedback_message = f"budget spent: {steps} of {budget} steps"
            return Status.SUCCESS
        if self.blackboard.get(bb.EXPLORATION_COMPLETE):
            self.feedback_message = f"nothing left to explore after {steps} of {budget} steps"
            return Status.SUCCESS
        self.feedback_message = f"{steps} of {budget} steps"
        return Status.FAILURE


class _Answer(py_trees.behaviour.Behaviour):
    """Writes the episode's answer from a stop decision."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in (bb.ANSWER_LOG, bb.CHOICES, bb.EXPLORATION_COMPLETE, bb.STOP_DECISION):
            self.blackboard.register_key(key, access=Access.READ)
        self.blackboard.register_key(bb.ANSWER, access=Access.WRITE)

    def decision(self, log: AnswerLog) -> StopDecision | None:
        raise NotImplementedError

    def update(self) -> Status:
        log: AnswerLog = self.blackboard.get(bb.ANSWER_LOG)
        if not len(log):
            self.feedback_message = "no step was scored, so there is nothing to answer from"
            return Status.FAILURE
        decision = self.decision(log)
        if decision is None:
            self.feedback_message = "the stopping rule has not decided"
            return Status.FAILURE
        self.blackboard.set(bb.ANSWER, self._record(decision, log))
        self.feedback_message = f"answer {decision.letter} from step {decision.from_step} ({decision.reason})"
        return Status.SUCCESS

    def _record(self, decision: StopDecision, log: AnswerLog) -> dict[str, Any]:
        scores = log.steps[decision.from_step - 1]
        return {
            "letter": decision.letter,
            "text": self.blackboard.get(bb.CHOICES)[LETTERS.index(decision.letter)],
            "stopped_after": decision.step,
            "from_step": decision.from_step,
            "relevance": round(scores.relevance, 4),
            "probability": round(scores.answer_probs[decision.letter], 4),
            "rule": decision.reason,
        }


class Answer(_Answer):
    """Gives the answer the stopping rule decided on (the single answer left in the conformal set).

    Args:
        name: the node's name.
    """

    def __init__(self, name: str = "Answer") -> None:
        super().__init__(name)

    def decision(self, log: AnswerLog) -> StopDecision | None:
        return self.blackboard.get(bb.STOP_DECISION)


class AnswerFallback(_Answer):
    """Answers argmax f̂ at the step of highest relevance when the robot must stop undecided.

    Args:
        name: the node's name.
    """

    def __init__(self, name: str = "AnswerFallback") -> None:
        super().__init__(name)

    def decision(self, log: AnswerLog) -> StopDecision:
        reason = "nothing left to explore" if self.blackboard.get(bb.EXPLORATION_COMPLETE) else "budget spent"
        return fallback_decision(log, reason)
