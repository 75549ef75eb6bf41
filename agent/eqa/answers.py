"""What the VLM said at each step, and the answer to give when the robot must stop.

Kept apart from the tree so stopping rules can be tested with plain lists of scores.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass(frozen=True)
class StepScores:
    """One step's scores: f̂ over the answer letters and the relevance Rel = P(Yes)."""

    step: int
    answer_probs: dict[str, float]
    relevance: float

    def best(self) -> str:
        """The letter of the answer scored likeliest at this step.

        Returns:
            The letter (the first of equals).
        """
        return max(self.answer_probs, key=lambda letter: self.answer_probs[letter])

    def to_record(self) -> dict[str, Any]:
        """The JSON form kept in result files and calibration files (5 decimals).

        Returns:
            The record.
        """
        return {"step": self.step, "answer_probs": {k: round(v, 5) for k, v in self.answer_probs.items()},
                "relevance": round(self.relevance, 5)}

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> StepScores:
        """A step read back from its `to_record` form.

        Args:
            record: the record.

        Returns:
            The step's scores.
        """
        return cls(record["step"], record["answer_probs"], record["relevance"])


def steps_from_records(records: list[dict[str, Any]]) -> list[StepScores]:
    """The steps of a recorded episode (`StepScores.to_record` lines), in order.

    Args:
        records: the episode's step records.

    Returns:
        The steps.
    """
    return [StepScores.from_record(record) for record in records]


@dataclass
class AnswerLog:
    """Every step's scores in order."""

    steps: list[StepScores] = field(default_factory=list)

    def add(self, answer_probs: dict[str, float], relevance: float) -> StepScores:
        """Score the next step: the VLM's answer probabilities and the view's relevance.

        Args:
            answer_probs: f̂, the probability of each answer letter.
            relevance: Rel, how relevant the view is to the question.

        Returns:
            The step's scores, numbered after the last.
        """
        scores = StepScores(len(self.steps) + 1, dict(answer_probs), float(relevance))
        self.steps.append(scores)
        return scores

    def __len__(self) -> int:
        return len(self.steps)

    def fallback(self) -> StepScores:
        """The step of highest relevance (the earliest on ties); its argmax f̂ is the answer.

        Returns:
            The step.

        Raises:
            ValueError: no step has been scored yet.
        """
        if not self.steps:
            raise ValueError("no step has been scored yet, so there is nothing to answer from")
        return max(self.steps, key=lambda s: (s.relevance, -s.step))
