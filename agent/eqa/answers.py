"""What the VLM said at each step, and the answer to give when the robot must stop.

Kept apart from the tree so stopping rules can be tested with plain lists of scores.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class StepScores:
    """One step's scores: f̂ over the answer letters and the relevance Rel = P(Yes)."""

    step: int
    answer_probs: dict[str, float]
    relevance: float

    def best(self) -> str:
        return max(self.answer_probs, key=lambda letter: self.answer_probs[letter])


@dataclass
class AnswerLog:
    """Every step's scores in order."""

    steps: list[StepScores] = field(default_factory=list)

    def add(self, answer_probs: dict[str, float], relevance: float) -> StepScores:
        scores = StepScores(len(self.steps) + 1, dict(answer_probs), float(relevance))
        self.steps.append(scores)
        return scores

    def __len__(self) -> int:
        return len(self.steps)

    def fallback(self) -> StepScores:
        """The step of highest relevance (the earliest on ties); its argmax f̂ is the answer."""
        if not self.steps:
            raise ValueError("no step has been scored yet, so there is nothing to answer from")
        return max(self.steps, key=lambda s: (s.relevance, -s.step))
