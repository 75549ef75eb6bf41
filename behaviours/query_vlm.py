"""QueryVLM: ask the VLM for f̂ (the answer distribution) and Rel (its confidence) on the newest frame.

The backend runs in a worker thread so a slow model (a remote server) never blocks the tick; the
behaviour stays RUNNING until both answers are in, and fails with the reason on a timeout or error.
"""

from __future__ import annotations

import time
from concurrent.futures import Future, ThreadPoolExecutor

import py_trees
from py_trees.common import Access, Status

from agent import blackboard as bb
from agent.eqa.answers import AnswerLog
from agent.eqa.prompts import YES_NO, answer_prompt, relevance_prompt
from agent.observation import Observation
from agent.runtime.timing import StageTimer
from agent.vlm.protocol import VisionLanguageModel, VisualQuery
from worlds.vocabulary import LETTERS


class QueryVLM(py_trees.behaviour.Behaviour):
    def __init__(self, vlm: VisionLanguageModel, timeout_s: float = 30.0,
                 timer: StageTimer | None = None, name: str = "QueryVLM") -> None:
        super().__init__(name)
        self.vlm = vlm
        self.timeout_s = timeout_s
        self.timer = timer
        self._executor = ThreadPoolExecutor(max_workers=1, thread_name_prefix="vlm")
        self._future: Future | None = None
        self._started = 0.0
        self.blackboard = self.attach_blackboard_client(name=name)
        for key in (bb.QUESTION, bb.CHOICES, bb.OBSERVATION):
            self.blackboard.register_key(key, access=Access.READ)
        self.blackboard.register_key(bb.ANSWER_LOG, access=Access.WRITE)

    def initialise(self) -> None:
        question = self.blackboard.get(bb.QUESTION)
        choices = self.blackboard.get(bb.CHOICES)
        observation = self.blackboard.get(bb.OBSERVATION)
        self._started = time.perf_counter()
        self._future = self._executor.submit(self._ask, observation, question, choices)

    def _ask(self, observation: Observation, question: str, choices: list[str]) -> tuple[dict[str, float], float]:
        answer = self.vlm.probabilities(VisualQuery(observation, answer_prompt(question, choices), LETTERS))
        relevance = self.vlm.probabilities(VisualQuery(observation, relevance_prompt(question), YES_NO))
        return answer, relevance["Yes"]

    def update(self) -> Status:
        elapsed = time.perf_counter() - self._started
        if self._future is None:
            return Status.FAILURE
        if not self._future.done():
            if elapsed > self.timeout_s:
                self._future.cancel()
                self.feedback_message = f"the {self.vlm.name} VLM gave no answer within {self.timeout_s:.1f} s"
                return Status.FAILURE
            self.feedback_message = f"asking the {self.vlm.name} VLM ({elapsed:.1f} s)"
            return Status.RUNNING
        try:
            answer, relevance = self._future.result()
        except Exception as error:  # any backend failure ends the step with its reason
            self.feedback_message = f"the {self.vlm.name} VLM failed: {type(error).__name__}: {error}"
            return Status.FAILURE
        if self.timer is not None:
            self.timer.record("vlm", elapsed * 1000.0)
        log: AnswerLog = self.blackboard.get(bb.ANSWER_LOG)
        scores = log.add(answer, relevance)
        self.feedback_message = f"step {scores.step}: best {scores.best()} ({answer[scores.best()]:.2f}), Rel {relevance:.2f}"
        return Status.SUCCESS

    def terminate(self, new_status: Status) -> None:
        if new_status == Status.INVALID and self._future is not None:
            self._future.cancel()
        self._future = None

    def shutdown(self) -> None:
        self._executor.shutdown(wait=False, cancel_futures=True)
