"""The `sim` VLM backend: a perception-grounded stand-in for a vision-language model.

It sees exactly what a real VLM would be given, and no more: the frame (pixels, depth, and the
instance segmentation with the labels of the instances in that frame, letters drawn on it for
visual prompting) and the prompt text. It never reads the home's hidden ground truth: a carton in a
closed fridge is not in the frame, so it does not exist for the simulator. Its model, with every
parameter, is described in docs/vlm-sim.md; in short:

- **Noticing.** Each instance that could answer the question is noticed with a probability that
  grows with its pixel area and falls with its distance, scaled by ``skill``.
- **Reading.** A noticed attribute (colour, category, room, count) is misread with ``misread``.
- **Answering.** Choices backed by what was noticed get ``evidence_logit``; without evidence a
  favourite choice fixed by the question text gets ``prior_logit`` (over-confidence on views that
  show nothing relevant). Gaussian ``logit_noise`` on every logit; padded choices get ``pad_logit``.
- **Relevance.** P(Yes) drawn from Beta distributions: noisy and poorly calibrated; surest on a
  view into the very storage a question asks about, standing open.
- **Directions.** LSV and GSV come from a commonsense table of where things are kept
  (`agent.vlm.commonsense`), the rooms visible around each drawn letter, whether the view leads on
  through a doorway, and noticed evidence.

Draws come from generators seeded by (``seed``, text, the frame's depth bytes), so the same frame
and prompt give the same answer. What is noticed is seeded by the question, so every prompt about
one frame agrees on what was seen.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass

import numpy as np

from agent.eqa.prompts import prompt_kind, read_answer_prompt, read_quoted_question
from agent.observation import InstanceLabel, Observation
from agent.vlm import commonsense
from agent.vlm.protocol import VisualQuery, softmax
from worlds.questions import ParsedQuestion, parse_question
from worlds.vocabulary import COLOURS, OBJECTS, PAD_CHOICE, room_names

_MISREAD_WORDS = {"colour": tuple(COLOURS), "category": tuple(OBJECTS), "room": room_names()}
#: Pixels an instance must fill in a region for the direction values to count it as seen there.
_SEEN_PX = 20


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
    relevance_inside: tuple[float, float] = (16.0, 1.5)
    relevance_room: tuple[float, float] = (3.0, 4.0)
    relevance_none: tuple[float, float] = (1.5, 4.0)
    direction_gain: float = 4.0
    mark_window: float = 0.15  # half-size of the region around a letter, as a share of the image width

    def __post_init__(self) -> None:
        for name in ("skill", "misread", "mark_window"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"vlm.sim.{name}: {value} must lie in [0, 1]")
        for name in ("notice_area_px", "notice_distance_m", "logit_noise", "direction_gain"):
            if getattr(self, name) < 0:
                raise ValueError(f"vlm.sim.{name}: must not be negative")


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
        kind = prompt_kind(query.prompt)
        rng = self._generator(query)
        if kind == "answer":
            question, choices = read_answer_prompt(query.prompt)
            return self._answer(query, rng, question, choices)
        question = read_quoted_question(query.prompt) or ""
        parsed = parse_question(question)
        if kind == "relevance" and set(query.candidates) == {"Yes", "No"}:
            return self._relevance(query, rng, question, parsed)
        if kind == "gsv" and set(query.candidates) == {"Yes", "No"}:
            return self._gsv(query, rng, parsed)
        if kind == "lsv" and query.marks:
            return self._lsv(query, rng, parsed)
        return {c: 1.0 / len(query.candidates) for c in query.candidates}

    def _generator(self, query: VisualQuery, text: str | None = None) -> np.random.Generator:
        frame = zlib.crc32(np.ascontiguousarray(query.observation.depth).tobytes())
        key = zlib.crc32((text if text is not None else query.prompt).encode())
        return np.random.default_rng([self.params.seed, key, frame])

    # --- answers -------------------------------------------------------------------------------

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
        for i in range(len(texts)):
            if i not in real:
                logits[i] = p.pad_logit
        return softmax(candidates, logits)

    def _relevance(self, query: VisualQuery, rng: np.random.Generator, question: str,
                   parsed: ParsedQuestion | None) -> dict[str, float]:
        p = self.params
        if parsed and self._evidence(query.observation, parsed, self._generator(query, question)):
            inside = parsed.template.hidden and _storage_open(_sightings(query.observation), parsed)
            shape = p.relevance_inside if inside else p.relevance_evidence
        elif parsed and parsed.room and _room_fraction(query.observation, parsed.room) >= p.room_view_fraction:
            shape = p.relevance_room
        else:
            shape = p.relevance_none
        return _yes_no(query.candidates, float(rng.beta(*shape)))

    def _evidence(self, observation: Observation, question: ParsedQuestion, rng: np.random.Generator) -> set[str]:
        """The lower-cased choice texts that what the model noticed in this frame supports."""
        asks = question.template.asks
        sightings = _sightings(observation)
        if asks in ("power", "door"):
            wanted = question.appliance or question.container
            noticed = self._noticed([s for s in sightings if s.label.category == wanted
                                     and s.label.room == question.room], rng)
            return {s.label.state for s in noticed if s.label.state}
        noticed = self._noticed([s for s in sightings if s.label.category in OBJECTS
                                 and _fits(s.label, question)], rng)
        room_in_view = bool(question.room) and _room_fraction(observation, question.room) >= self.params.room_view_fraction
        if asks == "yes/no":
            if noticed:
                return {"yes"}
            return {"no"} if self._absence_visible(sightings, question, room_in_view) else set()
        if asks == "count":
            if not noticed and not room_in_view:
                return set()
            count = len(noticed)
            if rng.random() < self.params.misread:
                count = max(0, count + int(rng.choice([-1, 1])))
            return {str(count)}
        supported = set()
        for sighting in noticed:
            value = getattr(sighting.label, asks)
            if rng.random() < self.params.misread:
                value = str(rng.choice([v for v in _MISREAD_WORDS[asks] if v != value]))
            supported.add(value)
        return supported

    def _absence_visible(self, sightings: list[_Sighting], question: ParsedQuestion, room_in_view: bool) -> bool:
        """Whether the frame shows where the thing would be, without it: the room, or the open storage."""
        if question.container is None:
            return room_in_view
        return _storage_open(sightings, question)

    def _noticed(self, sightings: list[_Sighting], rng: np.random.Generator) -> list[_Sighting]:
        p = self.params
        kept = []
        for sighting in sightings:
            size = 1.0 - np.exp(-sighting.area_px / p.notice_area_px)
            far = max(0.0, sighting.distance_m - p.notice_near_m)
            chance = p.skill * size * np.exp(-far / max(p.notice_distance_m, 1e-9))
            if rng.random() < chance:
                kept.append(sighting)
        return kept

    # --- directions (semantic values) ----------------------------------------------------------

    def _gsv(self, query: VisualQuery, rng: np.random.Generator, parsed: ParsedQuestion | None) -> dict[str, float]:
        """P(Yes) that some direction in view is worth exploring."""
        value = self._view_value(query.observation, parsed, None)
        logit = self.params.direction_gain * (value - 0.5) + rng.normal(0.0, self.params.logit_noise)
        return _yes_no(query.candidates, float(1.0 / (1.0 + np.exp(-logit))))

    def _lsv(self, query: VisualQuery, rng: np.random.Generator, parsed: ParsedQuestion | None) -> dict[str, float]:
        """P(letter) for the letters drawn on the image: which direction to explore."""
        observation = query.observation
        values = np.array([
            self._view_value(observation, parsed, query.marks[letter]) if letter in query.marks else -1.0
            for letter in query.candidates
        ])
        logits = self.params.direction_gain * values + rng.normal(0.0, self.params.logit_noise, len(values))
        logits[values < 0] = self.params.pad_logit
        return softmax(query.candidates, logits)

    def _view_value(self, observation: Observation, question: ParsedQuestion | None,
                    mark: tuple[float, float] | None) -> float:
        """How promising the view (or the region around a mark) is for the question, in [0, 1]."""
        seg = observation.segmentation
        if mark is not None:
            half = max(1, int(self.params.mark_window * seg.shape[1]))
            u, v = int(mark[0]), int(mark[1])
            seg = seg[max(0, v - half): v + half, max(0, u - half): u + half]
        labels = {label.id: label for label in observation.labels}
        ids, counts = np.unique(seg[seg >= 0], return_counts=True)
        if ids.size == 0:
            return 0.0
        storage = question is not None and question.template.hidden
        target = None if storage else _target_category(question)  # what is in storage is not in view
        rooms: dict[str, int] = {}
        seen: list[InstanceLabel] = []
        value = 0.0
        for instance, count in zip(ids.tolist(), counts.tolist()):
            label = labels.get(instance)
            if label is None:
                continue
            if label.category == "floor":
                rooms[label.room] = rooms.get(label.room, 0) + count
            elif count >= _SEEN_PX:
                seen.append(label)
            if target is not None and label.category == target and count >= _SEEN_PX:
                value = 1.0  # the thing itself is right there
        if storage:
            # What is in a closed piece of storage is seen by going to the piece: the piece in the
            # named room is the thing to go to, and what stands in view tells which room it is.
            value = max(value, _storage_value(seen, question))
        if rooms:
            if question is not None and question.room is not None:
                # The question names the room: that room is where to go, whatever usually lives where.
                named = commonsense.NAMED_ROOM_VALUE if question.room in rooms else commonsense.UNLISTED
                value = max(value, named)
            else:
                value = max(value, max(commonsense.affinity(target, room) for room in rooms))
            here = _room_at_feet(observation)
            if any(room != here for room in rooms):
                value = max(value, commonsense.DOORWAY_VALUE + 0.5 * value)
        return float(min(1.0, value))


def _storage_open(sightings: list[_Sighting], question: ParsedQuestion) -> bool:
    """Whether the frame shows the storage the question names (its kind, in its room) standing open."""
    return any(s.label.category == question.container and s.label.room == question.room
               and s.label.state == "open" for s in sightings)


def _storage_value(seen: list[InstanceLabel], question: ParsedQuestion) -> float:
    """For a question about what is in a piece of storage in a room: 1 when such a piece standing
    in that room is in view; else how strongly the things in view suggest that room (a toilet a
    bathroom, `commonsense.room_cue`), scaled to `commonsense.NAMED_ROOM_VALUE`."""
    if any(label.category == question.container and question.room in (None, label.room) for label in seen):
        return 1.0
    if question.room is None:
        return 0.0
    cues = [label.category for label in seen if label.category != question.container]
    return commonsense.NAMED_ROOM_VALUE * commonsense.room_cue(cues, question.room)


def _target_category(question: ParsedQuestion | None) -> str | None:
    if question is None:
        return None
    return question.category or question.appliance or question.container


def _fits(label: InstanceLabel, question: ParsedQuestion) -> bool:
    """Whether an instance matches every attribute the question names, except the one it asks."""
    asks = question.template.asks
    for attribute in ("category", "colour", "room"):
        wanted = getattr(question, attribute)
        if attribute != asks and wanted is not None and getattr(label, attribute) != wanted:
            return False
    return question.container is None or label.inside == question.container


def _yes_no(candidates: tuple[str, ...], yes: float) -> dict[str, float]:
    return {c: (yes if c == "Yes" else 1.0 - yes) for c in candidates}


def _room_fraction(observation: Observation, room: str) -> float:
    ids = [label.id for label in observation.labels if label.room == room and label.category == "floor"]
    return float(np.isin(observation.segmentation, ids).mean()) if ids else 0.0


def _room_at_feet(observation: Observation) -> str | None:
    """The room whose floor fills the bottom middle of the image: where the robot stands."""
    height, width = observation.segmentation.shape
    patch = observation.segmentation[int(height * 0.85):, width // 3: 2 * width // 3]
    floors = {label.id: label.room for label in observation.labels if label.category == "floor"}
    rooms = [floors[i] for i in patch.ravel().tolist() if i in floors]
    return max(set(rooms), key=rooms.count) if rooms else None


def _sightings(observation: Observation) -> list[_Sighting]:
    """Each labelled instance with its pixel area and mean depth in this frame."""
    seg = observation.segmentation.ravel()
    depth = observation.depth.ravel()
    ids, inverse, counts = np.unique(seg, return_inverse=True, return_counts=True)
    depth_sums = np.bincount(inverse, weights=depth)
    stats = {int(i): (int(n), float(s / n)) for i, n, s in zip(ids, counts, depth_sums)}
    return [_Sighting(label, *stats[label.id]) for label in observation.labels if label.id in stats]
