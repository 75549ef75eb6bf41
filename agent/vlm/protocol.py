"""The one question every VLM backend answers: given an image, a prompt and the candidate tokens,
how likely is each candidate to be the next token? Probabilities are normalised over the candidates.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from agent.observation import Observation


@dataclass(frozen=True)
class VisualQuery:
    """An image with a prompt. ``marks`` are letters drawn on the image for visual prompting, as
    letter -> (u, v) pixel; a backend that sends pixels draws them, the simulator reads them."""

    observation: Observation
    prompt: str
    candidates: tuple[str, ...]
    marks: dict[str, tuple[float, float]] = field(default_factory=dict)


class VisionLanguageModel(Protocol):
    name: str

    def probabilities(self, query: VisualQuery) -> dict[str, float]:
        """P(candidate) for each candidate, summing to 1.

        Args:
            query: the image, the prompt and the candidates.

        Returns:
            The probabilities.
        """
        ...


def softmax(candidates: tuple[str, ...], logits: np.ndarray) -> dict[str, float]:
    """Probabilities of ``candidates`` from their logits, the largest subtracted first so nothing overflows.

    Args:
        candidates: the candidates.
        logits: their logits.

    Returns:
        P per candidate.
    """
    shifted = np.exp(logits - np.max(logits))
    probs = shifted / shifted.sum()
    return {c: float(p) for c, p in zip(candidates, probs)}
