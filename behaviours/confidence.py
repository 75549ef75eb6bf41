"""Confidence: keep the stopping rule's state after every VLM step, and stop once it decides.

UpdatePredictionSet runs inside the step, right after QueryVLM, and hands the newest scores to the
stopping rule (conformal prediction by default, see agent.eqa.stopping). CheckConfidence succeeds
once the rule has decided; it guards both the "Confident" branch that answers and the step's next
move, so a robot that is confident does not drive anywhere first.
"""

from __future__ import annotations

import py_trees
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from agent.eqa.answers import AnswerLog
from agent.eqa.stopping import ConformalRule, StoppingRule


class UpdatePredictionSet(py_trees.behaviour.Behaviour):
    """Feeds each new step's f̂ and Rel to the stopping rule and publishes where it stands.

    Args:
        rule: the stopping rule.
        name: the node's name.
    """

    def __init__(self, rule: StoppingRule, name: str = "UpdatePredictionSet") -> None:
        super().__init__(name)
        self.rule = rule
        self.seen_steps = 0
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.ANSWER_LOG, access=Access.READ)
        for key in (bb.STOP_DECISION, bb.PREDICTION_SET, bb.Q_HAT, bb.EPSILON):
            self.blackboard.register_key(key, access=Access.WRITE)
        self.blackboard.set(bb.STOP_DECISION, None)
        self._publish_set()

    def update(self) -> Status:
        log: AnswerLog = self.blackboard.get(bb.ANSWER_LOG)
        if len(log) > self.seen_steps:  # a step is shown to the rule once, however often it is ticked
            self.seen_steps = len(log)
            decision = self.rule.observe(log)
            if decision is not None:
                self.blackboard.set(bb.STOP_DECISION, decision)
            self._publish_set()
        self.feedback_message = self.rule.describe()
        return Status.SUCCESS

    def _publish_set(self) -> None:
        conformal = isinstance(self.rule, ConformalRule)
        self.blackboard.set(bb.PREDICTION_SET, self.rule.prediction_set.sorted() if conformal else None)
        self.blackboard.set(bb.Q_HAT, self.rule.q_hat if conformal else None)
        self.blackboard.set(bb.EPSILON, self.rule.epsilon if conformal else None)


class CheckConfidence(py_trees.behaviour.Behaviour):
    """SUCCESS once the stopping rule has decided to stop; FAILURE while the robot should go on.

    Args:
        name: the node's name.
    """

    def __init__(self, name: str = "CheckConfidence") -> None:
        super().__init__(name)
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.STOP_DECISION, access=Access.READ)

    def update(self) -> Status:
        decision = self.blackboard.get(bb.STOP_DECISION)
        if decision is None:
            self.feedback_message = "not confident yet"
            return Status.FAILURE
        self.feedback_message = f"stop after step {decision.step}: {decision.reason}"
        return Status.SUCCESS
