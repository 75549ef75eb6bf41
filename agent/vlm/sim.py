"""The `sim` VLM backend: a perception-grounded stand-in for a vision-language model.

It sees exactly what a real VLM would be given, and no more: the frame (pixels, depth, and the
instance segmentation with the labels of the instances in that frame) and the prompt text. It never
reads the home's hidden ground truth. Its behaviour follows what Explore until Confident reports
of real VLMs, through explicit parameters (`SimParams`):

- **Noticing.** Each instance that could answer the question is noticed with probability
  ``skill · (1 − exp(−area_px / notice_area_px)) · exp(−max(0, distance − notice_near_m) / notice_distance_m)``:
  small or far things are often missed.
- **Reading.** A noticed instance's asked-for attribute (colour, category, room) is misread with
  probability ``misread``, becoming another word of the vocabulary.
- **Answering.** Choices backed by what was noticed get ``evidence_logit``. Without evidence the
  model still answers confidently from a biased prior: a favourite choice fixed by the question text
  gets ``prior_logit`` (the over-confidence on irrelevant views that makes entropy a poor stopping
  signal). Gaussian noise of ``logit_noise`` is added to every logit; padded choices get ``pad_logit``.
- **Relevance.** P(Yes) for "are you confident" is drawn from a Beta distribution: ``relevance_evidence``
  when evidence was noticed, ``relevance_room`` when the question's room fills part of the view,
  ``relevance_none`` otherwise. The Beta spreads make relevance noisy and poorly calibrated.

Every draw comes from generators seeded by (``seed``, the text, the frame's depth bytes), so the
same frame and prompt give the same answer. What is noticed depends on the question, not on the
prompt, so the answer and relevance prompts about one frame agree on what the model saw.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

from agent.eqa.prompts import read_answer_prompt, read_quoted_question
from agent.observation import InstanceLabel, Observation
from agent.vlm.protocol import VisualQuery, softmax
from worlds.vocabulary import COLOURS, OBJECTS, PAD_CHOICE, ROOM_TYPES, ParsedQuestion, parse_question

_VALUES = {"colour": tuple(COLOURS), "category": tuple(OBJECTS), "room": ROOM_TYPES}


@dataclass(frozen=True)
class SimParams:
    """The simulator's accuracy and miscalibration. Defaults give a capable but fallible model."""

    seed: int = 0
    skill: float = 0.9
    notice_area_px: float = 120.0
    notice_near_m: float = 1.5
    notice_distance_m: float = 4.0
    misread: float = 0.08
    evidence_logit: float = 4.0
    prior_logit: float = 2.5
    logit_noise: float = 0.6
    pad_logit: float = -6.0
    room_view_fraction: float = 0.12
    relevance_evidence: tuple[float, float] = (8.0, 2.0)
    relevance_room: tuple[float, float] = (3.0, 4.0)
    relevance_none: tuple[float, float] = (1.5, 4.0)

    def __post_init__(self) -> None:
        for name in ("skill", "misread"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"vlm.{name}: {value} must lie in [0, 1]")
        for name in ("notice_area_px", "notice_distance_m", "logit_noise"):
            if getattr(self, name) < 0:
                raise ValueError(f"vlm.{name}: must not be negative")


@dataclass(frozen=True)
class _Sighting:
    label: InstanceLabel
    area_px: int
    distance_m: float


class SimulatedVLM:
    """A `VisionLanguageModel` grounded only in the frame it is shown."""

    name = "sim"

    def __init__(self, params: SimParams = SimParams()) -> None:
        self.params = params

    def probabilities(self, query: VisualQuery) -> dict[str, float]:
        rng = self._generator(query)
        answer = read_answer_prompt(query.prompt)
        if answer is not None:
            question, choices = answer
            return self._answer(query, rng, question, choices)
        question = read_quoted_question(query.prompt)
        if question is not None and set(query.candidates) == {"Yes", "No"}:
            return self._relevance(query, rng, question)
        return {c: 1.0 / len(query.candidates) for c in query.candidates}

    def _generator(self, query: VisualQuery, text: str | None = None) -> np.random.Generator:
        frame = zlib.crc32(np.ascontiguousarray(query.observation.depth).tobytes())
        key = zlib.crc32((text if text is not None else query.prompt).encode())
        return np.random.default_rng([self.params.seed, key, frame])

    def _answer(self, query: VisualQuery, rng: np.random.Generator, question: str,
                choices: dict[str, str]) -> dict[str, float]:
        p = self.params
        parsed = parse_question(question)
        evidence = self._evidence(query.observation, parsed, self._generator(query, question)) if parsed else set()
        candidates = query.candidates
        logits = rng.normal(0.0, p.logit_noise, len(candidates))
        texts = [choices.get(letter, PAD_CHOICE).lower() for letter in candidates]
        real = [i for i, t in enumerate(texts) if t != PAD_CHOICE.lower()]
        backed = [i for i in real if texts[i] in evidence]
        if backed:
            logits[backed] += p.evidence_logit
        elif real:
            favourite = real[zlib.crc32(question.encode()) % len(real)]
            logits[favourite] += p.prior_logit
        for i, text in enumerate(texts):
            if i not in real:
                logits[i] = p.pad_logit
        return softmax(candidates, logits)

    def _relevance(self, query: VisualQuery, rng: np.random.Generator, question: str) -> dict[str, float]:
        p = self.params
        parsed = parse_question(question)
        if parsed and self._evidence(query.observation, parsed, self._generator(query, question)):
            shape = p.relevance_evidence
        elif parsed and parsed.room and self._room_fraction(query.observation, parsed.room) >= p.room_view_fraction:
            shape = p.relevance_room
        else:
            shape = p.relevance_none
        yes = float(rng.beta(*shape))
        return {c: (yes if c == "Yes" else 1.0 - yes) for c in query.candidates}

    def _evidence(self, observation: Observation, question: ParsedQuestion,
                  rng: np.random.Generator) -> set[str]:
        """The lower-cased choice texts that what the model noticed in this frame supports."""
        asks = question.template.asks
        supported = set()
        noticed_any = False
        for sighting in _sightings(observation):
            label = sighting.label
            if label.category not in OBJECTS or not self._fits(label, question, asks):
                continue
            if rng.random() >= self._notice_probability(sighting):
                continue
            noticed_any = True
            if asks == "yes/no":
                supported.add("yes")
                continue
            value = getattr(label, asks)
            if rng.random() < self.params.misread:
                value = str(rng.choice([v for v in _VALUES[asks] if v != value]))
            supported.add(value)
        if asks == "yes/no" and not noticed_any and question.room:
            if self._room_fraction(observation, question.room) >= self.params.room_view_fraction:
                supported.add("no")
        return supported

    @staticmethod
    def _fits(label: InstanceLabel, question: ParsedQuestion, asks: str) -> bool:
        for attribute in ("category", "colour", "room"):
            wanted = getattr(question, attribute)
            if attribute != asks and wanted is not None and getattr(label, attribute) != wanted:
                return False
        return True

    def _notice_probability(self, sighting: _Sighting) -> float:
        p = self.params
        size = 1.0 - np.exp(-sighting.area_px / p.notice_area_px)
        distance = np.exp(-max(0.0, sighting.distance_m - p.notice_near_m) / max(p.notice_distance_m, 1e-9))
        return float(p.skill * size * distance)

    @staticmethod
    def _room_fraction(observation: Observation, room: str) -> float:
        ids = [label.id for label in observation.labels if label.room == room]
        return float(np.isin(observation.segmentation, ids).mean()) if ids else 0.0


def _sightings(observation: Observation) -> list[_Sighting]:
    """Each labelled instance with its pixel area and mean depth in this frame."""
    seg = observation.segmentation.ravel()
    depth = observation.depth.ravel()
    ids, inverse, counts = np.unique(seg, return_inverse=True, return_counts=True)
    depth_sums = np.bincount(inverse, weights=depth)
    stats = {int(i): (int(n), float(s / n)) for i, n, s in zip(ids, counts, depth_sums)}
    return [_Sighting(label, *stats[label.id]) for label in observation.labels if label.id in stats]
