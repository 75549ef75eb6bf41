"""An EQA scenario for a home: one multiple-choice question, its answer, a budget and a start pose.

Questions come from `vocabulary.TEMPLATES` and are only asked when the home makes them unambiguous:
'What colour is the mug in the kitchen?' needs exactly one mug in the kitchen, 'Which room is the
red mug in?' exactly one red mug in the home, 'Which object in the kitchen is red?' exactly one red
thing in the kitchen (furniture included), and existence questions are 'yes' half of the time and
otherwise name a colour/category/room triple that truly is not there. Draws come from a generator
seeded with (seed, 1), a stream apart from the home's own.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import Any

import numpy as np

from worlds.freespace import clearance, free_space
from worlds.home import HomeSpec
from worlds.robot import ROBOT_RADIUS
from worlds.vocabulary import COLOURS, LETTERS, OBJECTS, PAD_CHOICE, ROOM_TYPES, TEMPLATES, Template

#: The start pose keeps at least this much space to walls, furniture and floor objects.
START_CLEARANCE = 0.5
_SCENARIO_STREAM = 1


@dataclass(frozen=True)
class Scenario:
    """One episode's question and ground truth. ``target`` holds the slots the question names."""

    seed: int
    question: str
    choices: tuple[str, str, str, str]
    answer: str
    answer_text: str
    kind: str
    asks: str
    target: dict[str, str | None]
    budget: int
    start_pose: tuple[float, float, float]

    def to_dict(self) -> dict[str, Any]:
        return {
            "seed": self.seed,
            "question": self.question,
            "choices": list(self.choices),
            "answer": self.answer,
            "answer_text": self.answer_text,
            "kind": self.kind,
            "asks": self.asks,
            "target": dict(self.target),
            "budget": self.budget,
            "start_pose": list(self.start_pose),
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Scenario:
        return cls(**{**data, "choices": tuple(data["choices"]), "start_pose": tuple(data["start_pose"])})


def budget_for(area_m2: float) -> int:
    """The paper's step budget T = int(3 * sqrt(area))."""
    return int(3 * math.sqrt(area_m2))


def make_scenario(home: HomeSpec, seed: int) -> Scenario:
    """Draw a question the home answers unambiguously, its shuffled choices and a clear start pose."""
    rng = np.random.default_rng([seed, _SCENARIO_STREAM])
    for index in rng.permutation(len(TEMPLATES)):
        template = TEMPLATES[int(index)]
        drawn = _draw_question(rng, home, template)
        if drawn is not None:
            break
    else:
        raise RuntimeError(f"home {home.seed}: no template has an unambiguous target")
    target, answer_text, distractors = drawn
    if template.asks == "yes/no":
        choices = ["Yes", "No", PAD_CHOICE, PAD_CHOICE]
    else:
        choices = [answer_text, *distractors]
        choices = [choices[int(i)] for i in rng.permutation(len(choices))]
    return Scenario(
        seed=seed,
        question=template.text.format(**{k: v for k, v in target.items() if v is not None}),
        choices=(choices[0], choices[1], choices[2], choices[3]),
        answer=LETTERS[choices.index(answer_text)],
        answer_text=answer_text,
        kind=template.kind,
        asks=template.asks,
        target=target,
        budget=budget_for(home.area_m2),
        start_pose=start_pose(home, rng),
    )


def _draw_question(
    rng: np.random.Generator, home: HomeSpec, template: Template
) -> tuple[dict[str, str | None], str, list[str]] | None:
    """(target slots, answer text, three distractors) for ``template``, or None if none is unambiguous."""
    objects = home.objects
    if template.asks == "yes/no":
        return _existence(rng, home)
    if template.asks == "category":  # Which object in the {room} is {colour}?
        things = Counter((o.room, o.colour) for o in objects) + Counter((f.room, f.colour) for f in home.furniture)
        unique = [o for o in objects if things[(o.room, o.colour)] == 1]
        slots = ("room", "colour")
    elif template.asks == "colour":  # What colour is the {category} in the {room}?
        counts = Counter((o.room, o.category) for o in objects)
        unique = [o for o in objects if counts[(o.room, o.category)] == 1]
        slots = ("room", "category")
    else:  # Which room is the {colour} {category} in?
        counts = Counter((o.colour, o.category) for o in objects)
        unique = [o for o in objects if counts[(o.colour, o.category)] == 1]
        slots = ("colour", "category")
    if not unique:
        return None
    item = unique[int(rng.integers(len(unique)))]
    answer = getattr(item, template.asks)
    target: dict[str, str | None] = {"category": None, "colour": None, "room": None}
    for slot in slots:
        target[slot] = getattr(item, slot)
    return target, answer, _distractors(rng, home, template.asks, answer)


def _distractors(rng: np.random.Generator, home: HomeSpec, asks: str, answer: str) -> list[str]:
    """Three wrong choices; for rooms, the home's other rooms first, so every choice is plausible."""
    if asks == "room":
        here = [r.name for r in home.rooms if r.name != answer]
        elsewhere = [r for r in ROOM_TYPES if r != answer and r not in here]
        pools = [here, elsewhere]
    else:
        pools = [[w for w in (OBJECTS if asks == "category" else COLOURS) if w != answer]]
    chosen: list[str] = []
    for pool in pools:
        take = min(3 - len(chosen), len(pool))
        chosen += [pool[int(i)] for i in rng.choice(len(pool), size=take, replace=False)]
    return chosen


def _existence(rng: np.random.Generator, home: HomeSpec) -> tuple[dict[str, str | None], str, list[str]]:
    """Yes half of the time (a real object); otherwise a near miss that is truly absent."""
    present = {(o.colour, o.category, o.room) for o in home.objects}
    if rng.random() < 0.5:
        colour, category, room = sorted(present)[int(rng.integers(len(present)))]
        return {"category": category, "colour": colour, "room": room}, "Yes", []
    rooms = [r.name for r in home.rooms]
    colours = list(COLOURS)
    while True:  # a near miss: a real object with its colour or its room changed
        base = home.objects[int(rng.integers(len(home.objects)))]
        if rng.random() < 0.5:
            triple = (colours[int(rng.integers(len(colours)))], base.category, base.room)
        else:
            triple = (base.colour, base.category, rooms[int(rng.integers(len(rooms)))])
        if triple not in present:
            colour, category, room = triple
            return {"category": category, "colour": colour, "room": room}, "No", []


def start_pose(home: HomeSpec, rng: np.random.Generator) -> tuple[float, float, float]:
    """A pose in the home's connected free space, at least `START_CLEARANCE` from any obstacle."""
    space = free_space(home, ROBOT_RADIUS)
    main = space.main_component()
    rows, cols = np.nonzero((space.components == main) & (space.clearance_m >= START_CLEARANCE + space.resolution))
    if rows.size == 0:
        raise RuntimeError(f"home {home.seed}: no free spot {START_CLEARANCE} m from every obstacle")
    for index in rng.permutation(rows.size):
        x, y = space.cell_centre(int(rows[index]), int(cols[index]))
        x, y = round(x, 3), round(y, 3)
        if clearance(home, x, y) >= START_CLEARANCE:
            return (x, y, round(float(rng.uniform(-math.pi, math.pi)), 4))
    raise RuntimeError(f"home {home.seed}: no free spot passed the exact clearance check")
