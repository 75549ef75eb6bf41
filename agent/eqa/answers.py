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
        return max(self.answer_probs, key=lambda letter: self.answer_probs[letter])

    def to_record(self) -> dict[str, Any]:
        """The JSON form kept in result files and calibration files (5 decimals)."""
        return {"step": self.step, "answer_probs": {k: round(v, 5) for k, v in self.answer_probs.items()},
                "relevance": round(self.relevance, 5)}

    @classmethod
    def from_record(cls, record: dict[str, Any]) -> StepScores:
        return cls(record["step"], record["answer_probs"], record["relevance"])


def steps_from_records(records: list[dict[str, Any]]) -> list[StepScores]:
    """The steps of a recorded episode (`StepScores.to_record` lines), in order."""
    return [StepScores.from_record(record) for record in records]


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
