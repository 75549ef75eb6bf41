"""Stopping and answering: when the budget is spent or nothing is left, answer from the best step."""

from __future__ import annotations

import py_trees
from py_trees.common import Access, Status

from agent import blackboard as bb
from worlds.vocabulary import LETTERS


class ShouldStop(py_trees.behaviour.Behaviour):
    """SUCCESS once the step budget is spent or no frontier is left; FAILURE while exploring."""

    def __init__(self, name: str = "BudgetSpent") -> None:
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


class AnswerFallback(py_trees.behaviour.Behaviour):
    """Answers argmax f̂ at the step of highest relevance (the paper's rule without early stopping)."""

    def __init__(self, name: str = "AnswerFallback") -> None:
        super().__init__(name)
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in (bb.ANSWER_LOG, bb.CHOICES, bb.EXPLORATION_COMPLETE):
            self.blackboard.register_key(key, access=Access.READ)
        self.blackboard.register_key(bb.ANSWER, access=Access.WRITE)

    def update(self) -> Status:
        log = self.blackboard.get(bb.ANSWER_LOG)
        if not len(log):
            self.feedback_message = "no step was scored, so there is nothing to answer from"
            return Status.FAILURE
        best = log.fallback()
        letter = best.best()
        choices = self.blackboard.get(bb.CHOICES)
        reason = "nothing left to explore" if self.blackboard.get(bb.EXPLORATION_COMPLETE) else "budget spent"
        self.blackboard.set(bb.ANSWER, {
            "letter": letter,
            "text": choices[LETTERS.index(letter)],
            "from_step": best.step,
            "relevance": round(best.relevance, 4),
            "probability": round(best.answer_probs[letter], 4),
            "rule": f"argmax f̂ at the most relevant step ({reason})",
        })
        self.feedback_message = f"answer {letter} from step {best.step} (Rel {best.relevance:.2f})"
        return Status.SUCCESS
