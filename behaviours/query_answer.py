"""QueryVLM: ask the VLM for f̂ (the answer distribution) and Rel (its confidence) on the newest frame
(or, after the act branch opened storage, on what it saw inside: ``view=bb.INSIDE_VIEW``)."""

from __future__ import annotations

from py_trees.common import Access, Status

from behaviours import blackboard as bb
from agent.eqa.answers import AnswerLog
from agent.eqa.prompts import YES_NO, answer_prompt, relevance_prompt
from agent.observation import Observation
from agent.timing import StageTimer
from agent.vlm.protocol import VisionLanguageModel, VisualQuery
from behaviours.async_vlm import AsyncVLMQuery
from worlds.bus.questions import LETTERS


class QueryVLM(AsyncVLMQuery):
    """Asks the VLM for f̂ (the answer distribution) and Rel (its confidence) on the view, and logs the step.

    Args:
        vlm: the model asked.
        timeout_s: how long an answer may take.
        timer: times the queries, if given.
        name: the node's name.
        view: the blackboard key of the view asked about.
    """

    def __init__(self, vlm: VisionLanguageModel, timeout_s: float = 30.0,
                 timer: StageTimer | None = None, name: str = "QueryVLM", view: str = bb.OBSERVATION) -> None:
        super().__init__(name, vlm, timeout_s, timer)
        self.view = view
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in (bb.QUESTION, bb.CHOICES, view):
            self.blackboard.register_key(key, access=Access.READ)
        self.blackboard.register_key(bb.ANSWER_LOG, access=Access.WRITE)

    def inputs(self) -> tuple[Observation, str, list[str]]:
        return (self.blackboard.get(self.view), self.blackboard.get(bb.QUESTION), self.blackboard.get(bb.CHOICES))

    def ask(self, observation: Observation, question: str, choices: list[str]) -> tuple[dict[str, float], float]:
        answer = self.vlm.probabilities(VisualQuery(observation, answer_prompt(question, choices), LETTERS))
        relevance = self.vlm.probabilities(VisualQuery(observation, relevance_prompt(question), YES_NO))
        return answer, relevance["Yes"]

    def use(self, answer: tuple[dict[str, float], float]) -> Status:
        probs, relevance = answer
        log: AnswerLog = self.blackboard.get(bb.ANSWER_LOG)
        scores = log.add(probs, relevance)
        self.feedback_message = f"step {scores.step}: best {scores.best()} ({probs[scores.best()]:.2f}), Rel {relevance:.2f}"
        return Status.SUCCESS
