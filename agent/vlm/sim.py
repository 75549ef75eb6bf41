"""The `sim` VLM backend: a perception-grounded stand-in for a vision-language model.

It sees exactly what a real VLM would be given, and no more: the frame (pixels, depth, and the
instance segmentation with the labels of the instances in that frame: what each thing is, its
colour, a visible state, and the storage it is seen inside when that storage's interior is in
view; letters drawn on it for visual prompting) and the prompt text. No label names a room: the
model tells a kitchen from a bedroom by the furniture it sees. It never reads the home's hidden
ground truth: a carton in a closed fridge is not in the frame, so it does not exist for it. Its
model, with every parameter and what the defaults measure on rendered frames, is in
docs/vlm-sim.md; in short:

- **Seeing** (`agent.vlm.sim_frame`). Each instance is noticed with a probability that grows with
  its pixel area and falls with its distance, scaled by ``skill``; which room each part of the
  frame shows is read off the furniture standing there, misjudged with ``room_error``.
- **Reading** (`agent.vlm.sim_evidence`). What it noticed backs choices (a noticed attribute is
  misread with ``misread``), surely or as a guess.
- **Answering.** Sure evidence adds ``evidence_logit`` to the choices it backs, a guess
  ``prior_logit``; without either a favourite choice fixed by the question text gets
  ``prior_logit`` (over-confidence on views that show nothing relevant). Gaussian ``logit_noise``
  on every logit; padded choices get ``pad_logit``.
- **Relevance.** P(Yes) drawn from Beta distributions by what the frame settles: surest on a view
  into the very storage a question asks about, then on sure evidence, then on a guess, least on
  views that back nothing.
- **Directions** (`agent.vlm.sim_directions`). LSV and GSV from common sense about where things
  are kept, the rooms around each letter, whether the view leads on, and the thing itself.

Draws come from generators seeded by (``seed``, text, the frame's depth bytes), so the same frame
and prompt give the same answer. What is seen is seeded by the question, so every prompt about one
frame agrees on what was seen.
"""

from __future__ import annotations

import zlib

import numpy as np

from agent.eqa.prompts import prompt_kind, read_answer_prompt, read_quoted_question
from agent.observation import Observation
from agent.vlm.protocol import VisualQuery, softmax
from agent.vlm.sim_directions import view_value
from agent.vlm.sim_evidence import NONE, Evidence, evidence
from agent.vlm.sim_frame import FrameTake
from agent.vlm.sim_params import SimParams
from worlds.questions import ParsedQuestion, parse_question
from worlds.bus.questions import PAD_CHOICE

__all__ = ["SimParams", "SimulatedVLM"]


class SimulatedVLM:
    """A `VisionLanguageModel` grounded only in the frame it is shown.

    Args:
        params: how well it notices, judges rooms and answers.
    """

    name = "sim"

    def __init__(self, params: SimParams = SimParams()) -> None:
        self.params = params

    def probabilities(self, query: VisualQuery) -> dict[str, float]:
        """P(candidate) as the simulated model answers: from what the frame shows about the question.

        Args:
            query: the image, the prompt and the candidates.

        Returns:
            The probabilities, summing to 1.
        """
        kind = prompt_kind(query.prompt)
        rng = self._generator(query.observation, query.prompt)
        if kind == "answer":
            question, choices = read_answer_prompt(query.prompt)
            return self._answer(query, rng, question, choices)
        question = read_quoted_question(query.prompt) or ""
        parsed = parse_question(question)
        if kind == "relevance" and set(query.candidates) == {"Yes", "No"}:
            return self._relevance(query, rng, question, parsed)
        if kind == "gsv" and set(query.candidates) == {"Yes", "No"}:
            return self._gsv(query, rng, question, parsed)
        if kind == "lsv" and query.marks:
            return self._lsv(query, rng, question, parsed)
        return {c: 1.0 / len(query.candidates) for c in query.candidates}

    def rooms_taken(self, observation: Observation, question: str) -> dict[int, str | None]:
        """The room kind the model takes each floor in view for, asked about ``question`` (None
        where nothing in view names it): what every prompt about that question on this frame
        answers from. For measuring how it judges rooms (`agent.vlm.measure.room_judgement`).

        Args:
            observation: the frame.
            question: the question.

        Returns:
            The room kind (or None) by floor instance.
        """
        take, _ = self._take(observation, question)
        return {floor: take.region_kind(floor) for floor in take.rooms.floors}

    def _generator(self, observation: Observation, text: str) -> np.random.Generator:
        frame = zlib.crc32(np.ascontiguousarray(observation.depth).tobytes())
        return np.random.default_rng([self.params.seed, zlib.crc32(text.encode()), frame])

    def _take(self, observation: Observation, question: str) -> tuple[FrameTake, np.random.Generator]:
        """The frame as the model takes it in for ``question``, and the generator that goes on
        to draw its reading: both seeded by the question, not the prompt."""
        rng = self._generator(observation, question)
        return FrameTake(observation, self.params, rng), rng

    def _evidence(self, query: VisualQuery, question: str, parsed: ParsedQuestion | None) -> Evidence:
        if parsed is None:
            return NONE
        take, rng = self._take(query.observation, question)
        return evidence(take, parsed, rng)

    # --- answers -------------------------------------------------------------------------------

    def _answer(self, query: VisualQuery, rng: np.random.Generator, question: str,
                choices: dict[str, str]) -> dict[str, float]:
        p = self.params
        found = self._evidence(query, question, parse_question(question))
        candidates = query.candidates
        logits = rng.normal(0.0, p.logit_noise, len(candidates))
        texts = [choices.get(letter, PAD_CHOICE).lower() for letter in candidates]
        real = [i for i, t in enumerate(texts) if t != PAD_CHOICE.lower()]
        backed = [i for i in real if texts[i] in found.backed]
        if backed:
            logits[backed] += p.evidence_logit if found.sure else p.prior_logit
        elif real:
            favourite = real[zlib.crc32(question.encode()) % len(real)]
            logits[favourite] += p.prior_logit
        for i in range(len(texts)):
            if i not in real:
                logits[i] = p.pad_logit
        return softmax(candidates, logits)

    def _relevance(self, query: VisualQuery, rng: np.random.Generator, question: str,
                   parsed: ParsedQuestion | None) -> dict[str, float]:
        p = self.params
        found = self._evidence(query, question, parsed)
        if found.sure and found.inside:
            shape = p.relevance_inside
        elif found.sure:
            shape = p.relevance_evidence
        elif found.backed:
            shape = p.relevance_guess
        else:
            shape = p.relevance_none
        return _yes_no(query.candidates, float(rng.beta(*shape)))

    # --- directions (semantic values) ----------------------------------------------------------

    def _gsv(self, query: VisualQuery, rng: np.random.Generator, question: str,
             parsed: ParsedQuestion | None) -> dict[str, float]:
        """P(Yes) that some direction in view is worth exploring."""
        take, _ = self._take(query.observation, question)
        value = view_value(take, parsed, None, self.params.mark_window)
        logit = self.params.direction_gain * (value - 0.5) + rng.normal(0.0, self.params.logit_noise)
        return _yes_no(query.candidates, float(1.0 / (1.0 + np.exp(-logit))))

    def _lsv(self, query: VisualQuery, rng: np.random.Generator, question: str,
             parsed: ParsedQuestion | None) -> dict[str, float]:
        """P(letter) for the letters drawn on the image: which direction to explore."""
        take, _ = self._take(query.observation, question)
        values = np.array([
            view_value(take, parsed, query.marks[letter], self.params.mark_window) if letter in query.marks else -1.0
            for letter in query.candidates
        ])
        logits = self.params.direction_gain * values + rng.normal(0.0, self.params.logit_noise, len(values))
        logits[values < 0] = self.params.pad_logit
        return softmax(query.candidates, logits)


def _yes_no(candidates: tuple[str, ...], yes: float) -> dict[str, float]:
    return {c: (yes if c == "Yes" else 1.0 - yes) for c in candidates}
