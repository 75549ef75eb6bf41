"""Measuring a VLM backend on frames with known answers: the properties docs/vlm-sim.md states.

Explore until Confident leans on three behaviours of its VLM, and any backend can be measured for
them over a list of cases (a frame, a question, its choices and the right letter):

- **accuracy in view**: with the question's target in clear view (at least ``min_share`` of the
  frame), how often argmax f̂ is the right letter;
- **confident bias on irrelevant views**: with nothing of the question in view, how low the
  entropy of f̂ stays (normalised by the log of the number of real choices: 1 is uniform) and how
  often the same letter wins for one question whatever the view (the failure of the Entropy rule);
- **relevance that tells right from wrong**: the ROC AUC of Rel(x) at separating the frames whose
  argmax f̂ is right from those where it is wrong, over every case.

Pure: the backend is called through its `probabilities`; nothing here knows how frames were made.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from agent.eqa.prompts import YES_NO, answer_prompt, relevance_prompt
from agent.observation import Observation
from agent.vlm.protocol import VisionLanguageModel, VisualQuery
from agent.vlm.sim import SimulatedVLM
from worlds.bus.questions import LETTERS, PAD_CHOICE


@dataclass(frozen=True)
class Case:
    """One frame and question with its right letter; ``target_share``: the share of the frame the
    question's target fills (0 when it is not wholly in view); ``relevant``: whether anything of
    the kind the question asks about is in view; ``floor_rooms``: the true room kind of each floor
    instance in view, for measuring how a model judges rooms (`room_judgement`)."""

    observation: Observation
    question: str
    choices: tuple[str, ...]
    answer: str
    target_share: float
    relevant: bool
    floor_rooms: dict[int, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Reply:
    """The backend's f̂ and Rel for one case."""

    probabilities: dict[str, float]
    relevance: float

    @property
    def argmax(self) -> str:
        return max(self.probabilities, key=self.probabilities.__getitem__)


@dataclass(frozen=True)
class Report:
    """The measured properties (module docstring), with how many cases each rests on."""

    cases: int
    in_view: int
    accuracy_in_view: float
    irrelevant: int
    accuracy_irrelevant: float
    entropy_irrelevant: float
    same_answer_irrelevant: float
    accuracy: float
    relevance_auc: float


def ask(vlm: VisionLanguageModel, case: Case) -> Reply:
    """The answer and relevance prompts of Explore until Confident, on the case's frame.

    Args:
        vlm: the model.
        case: the frame and its question.

    Returns:
        The answer probabilities and the relevance.
    """
    choices = list(case.choices)
    probabilities = vlm.probabilities(VisualQuery(case.observation, answer_prompt(case.question, choices), LETTERS))
    relevance = vlm.probabilities(VisualQuery(case.observation, relevance_prompt(case.question), YES_NO))["Yes"]
    return Reply(probabilities, relevance)


def measure(vlm: VisionLanguageModel, cases: Sequence[Case], min_share: float = 0.02) -> Report:
    """Ask ``vlm`` about every case and measure the properties (module docstring). A property with
    no case to rest on is NaN.

    Args:
        vlm: the model.
        cases: the frames and their questions.
        min_share: the least share of the image the target fills to count as in view.

    Returns:
        The report.
    """
    replies = [ask(vlm, case) for case in cases]
    right = np.array([reply.argmax == case.answer for case, reply in zip(cases, replies)])
    in_view = np.array([case.target_share >= min_share for case in cases])
    irrelevant = np.array([not case.relevant for case in cases])
    entropies = np.array([normalised_entropy(reply.probabilities, case.choices) for case, reply in zip(cases, replies)])
    return Report(
        cases=len(cases),
        in_view=int(in_view.sum()),
        accuracy_in_view=_mean(right[in_view]),
        irrelevant=int(irrelevant.sum()),
        accuracy_irrelevant=_mean(right[irrelevant]),
        entropy_irrelevant=_mean(entropies[irrelevant]),
        same_answer_irrelevant=_same_answer([((c.question, c.choices), r.argmax)
                                             for c, r, i in zip(cases, replies, irrelevant) if i]),
        accuracy=_mean(right),
        relevance_auc=roc_auc(np.array([reply.relevance for reply in replies]), right),
    )


@dataclass(frozen=True)
class RoomJudgement:
    """How the simulated VLM took the rooms of the floors in view: ``floors`` seen, ``judged`` (a
    room kind named by what stands there), and ``wrong`` (judged, but not the floor's true kind)."""

    floors: int
    judged: int
    wrong: int

    @property
    def error(self) -> float:
        """The share of judged floors taken for the wrong kind of room."""
        return self.wrong / self.judged if self.judged else float("nan")


def room_judgement(vlm: SimulatedVLM, cases: Sequence[Case]) -> RoomJudgement:
    """Compare the room kind the simulator takes each floor in view for, asked each case's
    question, with the floor's true kind.

    Args:
        vlm: the simulated model.
        cases: the frames and their questions.

    Returns:
        How many floors were judged, and how many wrongly.
    """
    floors = judged = wrong = 0
    for case in cases:
        taken = vlm.rooms_taken(case.observation, case.question)
        for floor, truth in case.floor_rooms.items():
            floors += 1
            if taken.get(floor) is not None:
                judged += 1
                wrong += taken[floor] != truth
    return RoomJudgement(floors, judged, wrong)


def normalised_entropy(probabilities: dict[str, float], choices: Sequence[str]) -> float:
    """H(f̂) / ln(number of real choices): 1 for a uniform answer over them, 0 for a certain one.

    Args:
        probabilities: f̂ per letter.
        choices: the choices (padding is not a real choice).

    Returns:
        The normalised entropy.
    """
    real = [LETTERS[i] for i, choice in enumerate(choices) if choice != PAD_CHOICE]
    p = np.array([probabilities[letter] for letter in real])
    p = p / p.sum()
    h = float(-(p[p > 0] * np.log(p[p > 0])).sum())
    return h / math.log(len(real)) if len(real) > 1 else 0.0


def roc_auc(scores: ArrayLike, positive: ArrayLike) -> float:
    """P(score of a random positive > score of a random negative), ties counted half (the
    Mann-Whitney U statistic over n_pos·n_neg); NaN without both kinds.

    Args:
        scores: the scores.
        positive: which are positive.

    Returns:
        The AUC, or NaN.
    """
    scores, positive = np.asarray(scores, dtype=float), np.asarray(positive, dtype=bool)
    pos, neg = scores[positive], scores[~positive]
    if pos.size == 0 or neg.size == 0:
        return float("nan")
    greater = (pos[:, None] > neg[None, :]).sum()
    ties = (pos[:, None] == neg[None, :]).sum()
    return float((greater + 0.5 * ties) / (pos.size * neg.size))


def _same_answer(answers: list[tuple[tuple[str, tuple[str, ...]], str]]) -> float:
    """The share of answers that are their question's most common one (over questions, with
    their choices, asked on more than one view): 1 when a question gets one favourite whatever
    the view."""
    by_question: dict[tuple[str, tuple[str, ...]], list[str]] = {}
    for question, letter in answers:
        by_question.setdefault(question, []).append(letter)
    repeated = [letters for letters in by_question.values() if len(letters) > 1]
    if not repeated:
        return float("nan")
    return sum(Counter(letters).most_common(1)[0][1] for letters in repeated) / sum(len(ls) for ls in repeated)


def _mean(values: np.ndarray) -> float:
    return float(values.mean()) if values.size else float("nan")
