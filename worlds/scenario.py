"""An EQA scenario for a home: one multiple-choice question, its answer, a budget and a start pose.

The question's category is drawn with the paper's shares (`questions.CATEGORY_SHARES`), then a
template of that category the home can ask unambiguously: 'What colour is the mug in the kitchen?'
needs exactly one mug in the kitchen that can be seen, 'Is there any milk carton in the fridge in
the kitchen?' exactly one closed fridge in the kitchen. A camera tells a room's kind by what stands
in it, never which of two bedrooms it is, so a question names, and a location question answers
with, only rooms whose kind the home has once (`nameable_rooms`), by that kind; room choices are
all different kinds. Only hidden-evidence templates ask about
what is out of sight; the others count and name only what looking can find. Four choices, padded
with `PAD_CHOICE` when fewer are real, shuffled except yes/no, on/off and open/closed, and counts,
which stay in their natural order. Draws come from a generator seeded with (seed, 1), a stream
apart from the home's own.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from worlds.facts import HomeFacts
from worlds.freespace import clearance, free_space
from worlds.home import HomeSpec
from worlds.questions import CATEGORY_SHARES, ON_OFF, OPEN_CLOSED, TEMPLATES, YES_NO, Template, format_question
from worlds.robot import ROBOT_RADIUS
from worlds.vocabulary import COLOURS, OBJECTS, ROOM_TYPES
from worlds.bus.questions import LETTERS, PAD_CHOICE

#: The start pose keeps at least this much space to walls, furniture and floor objects.
START_CLEARANCE = 0.5
_SCENARIO_STREAM = 1
MAX_COUNT = 6

Slots = dict[str, str]
Draw = tuple[Slots, str, list[str]]  # the slots the question names, the answer text, the choices


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
    target: dict[str, str | None]  # the slots the question names; None for those it does not
    budget: int
    start_pose: tuple[float, float, float]

    def to_dict(self) -> dict[str, Any]:
        """The scenario as plain data, for suites and results.

        Returns:
            The dict.
        """
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
        """A scenario read back from its `to_dict` form.

        Args:
            data: the dict.

        Returns:
            The scenario.
        """
        return cls(**{**data, "choices": tuple(data["choices"]), "start_pose": tuple(data["start_pose"])})


def budget_for(area_m2: float) -> int:
    """The paper's step budget T = int(3 * sqrt(area)).

    Args:
        area_m2: the home's floor area.

    Returns:
        T, in steps.
    """
    return int(3 * math.sqrt(area_m2))


def make_scenario(home: HomeSpec, seed: int, kinds: tuple[str, ...] | None = None,
                  hidden: bool | None = None) -> Scenario:
    """Draw a question the home answers unambiguously, its choices and a clear start pose.

    ``kinds`` limits the categories (default: all, drawn with the paper's shares); ``hidden``
    True asks only hidden-evidence questions, False never, None either.

    Args:
        home: the home.
        seed: the draws' seed.
        kinds: the question categories allowed (all when None).
        hidden: whether to ask hidden-evidence questions only, never, or either (None).

    Returns:
        The scenario.

    Raises:
        ValueError: no template has those kinds.
        RuntimeError: the home answers no such question unambiguously.
    """
    rng = np.random.default_rng([seed, _SCENARIO_STREAM])
    facts = HomeFacts(home)
    templates = [t for t in TEMPLATES if (kinds is None or t.kind in kinds) and (hidden is None or t.hidden == hidden)]
    if not templates:
        raise ValueError(f"no question template has kinds={kinds} and hidden={hidden}")
    for template in _template_order(rng, templates):
        drawn = _DRAWERS[template.text](rng, facts)
        if drawn is not None:
            break
    else:
        raise RuntimeError(f"home {home.seed}: no question of kinds={kinds}, hidden={hidden} is unambiguous here")
    slots, answer_text, choices = drawn
    return Scenario(
        seed=seed,
        question=format_question(template, **slots),
        choices=(choices[0], choices[1], choices[2], choices[3]),
        answer=LETTERS[choices.index(answer_text)],
        answer_text=answer_text,
        kind=template.kind,
        asks=template.asks,
        target={key: slots.get(key) for key in ("category", "colour", "room", "container", "appliance")},
        budget=budget_for(home.area_m2),
        start_pose=start_pose(home, rng),
    )


def _template_order(rng: np.random.Generator, templates: list[Template]) -> list[Template]:
    """Templates in a random order whose first pick follows the paper's category shares."""
    weights = np.array([CATEGORY_SHARES[t.kind] / sum(u.kind == t.kind for u in templates) for t in templates])
    order = rng.choice(len(templates), size=len(templates), replace=False, p=weights / weights.sum())
    return [templates[int(i)] for i in order]


def _pick(rng: np.random.Generator, options: list[Any]) -> Any:
    return options[int(rng.integers(len(options)))]


def _shuffled(rng: np.random.Generator, answer: str, distractors: list[str]) -> list[str]:
    choices = [answer, *distractors]
    return [choices[int(i)] for i in rng.permutation(len(choices))]


def _padded(choices: tuple[str, ...]) -> list[str]:
    return [*choices, *[PAD_CHOICE] * (4 - len(choices))]


def _words_but(rng: np.random.Generator, words: list[str], answer: str, preferred: list[str] | None = None) -> list[str]:
    """Three words other than ``answer``, from ``preferred`` first (so every choice is plausible)."""
    chosen: list[str] = []
    for pool in (preferred or [], words):
        pool = [w for w in dict.fromkeys(pool) if w != answer and w not in chosen]
        take = min(3 - len(chosen), len(pool))
        chosen += [pool[int(i)] for i in rng.choice(len(pool), size=take, replace=False)] if take else []
    return chosen


def nameable_rooms(home: HomeSpec) -> set[str]:
    """The rooms a question may name: those whose kind the home has once (and whose name is then
    that kind). "The bedroom" of a home with two is not a room any camera could pick out.

    Args:
        home: the home.

    Returns:
        The rooms' names.
    """
    kinds = Counter(room.kind for room in home.rooms)
    return {room.name for room in home.rooms if kinds[room.kind] == 1}


def _unique_visible(rng: np.random.Generator, facts: HomeFacts, slots: tuple[str, ...],
                    counted: list[Any]) -> Any | None:
    """A visible object in a nameable room that is the only one among ``counted`` with its values
    of ``slots``, so a question naming those values has one answer; None when there is none."""
    counts = Counter(tuple(getattr(thing, slot) for slot in slots) for thing in counted)
    rooms = nameable_rooms(facts.home)
    unique = [o for o in facts.visible_objects()
              if o.room in rooms and counts[tuple(getattr(o, slot) for slot in slots)] == 1]
    return _pick(rng, unique) if unique else None


def _object_colour_in_room(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """Which object in the {room} is {colour}? (one visible thing of that colour in the room)"""
    item = _unique_visible(rng, facts, ("room", "colour"), [*facts.home.objects, *facts.home.furniture])
    if item is None:
        return None
    return {"room": item.room, "colour": item.colour}, item.category, _shuffled(
        rng, item.category, _words_but(rng, list(OBJECTS), item.category))


def _colour_of_object(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """What colour is the {category} in the {room}? (one such object in the room, visible)"""
    item = _unique_visible(rng, facts, ("room", "category"), facts.home.objects)
    if item is None:
        return None
    return {"room": item.room, "category": item.category}, item.colour, _shuffled(
        rng, item.colour, _words_but(rng, list(COLOURS), item.colour))


def _unique_storage(facts: HomeFacts, closed: bool) -> list:
    """Storage pieces, closed or open, the only ones of their kind in a nameable room."""
    counts = Counter((f.room, f.category) for f in facts.storage())
    rooms = nameable_rooms(facts.home)
    return [f for f in facts.storage()
            if f.room in rooms and counts[(f.room, f.category)] == 1 and facts.is_open(f) != closed]


def _inside_storage(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """What is inside the {container} in the {room}? (a closed piece holding exactly one object)"""
    holding = {}
    for item in facts.home.objects:
        storage = facts.storage_of(item)
        if storage is not None and facts.is_hidden(item):
            holding.setdefault(storage.instance_id, []).append(item)
    options = [f for f in _unique_storage(facts, closed=True) if len(holding.get(f.instance_id, [])) == 1]
    if not options:
        return None
    storage = _pick(rng, options)
    item = holding[storage.instance_id][0]
    return {"container": storage.category, "room": storage.room}, item.category, _shuffled(
        rng, item.category, _words_but(rng, list(OBJECTS), item.category))


def _count_in_room(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """How many {plural} are there in the {room}? (all of them in view: none hidden)"""
    counts = Counter((o.room, o.category) for o in facts.home.objects)
    hidden = {(o.room, o.category) for o in facts.home.objects if facts.is_hidden(o)}
    rooms = nameable_rooms(facts.home)
    options = sorted(key for key, n in counts.items() if key not in hidden and n <= MAX_COUNT and key[0] in rooms)
    if not options:
        return None
    room, category = _pick(rng, options)
    answer = counts[(room, category)]
    others = [n for n in range(MAX_COUNT + 1) if n != answer]
    numbers = sorted([answer, *(others[int(i)] for i in rng.choice(len(others), size=3, replace=False))])
    return {"room": room, "category": category}, str(answer), [str(n) for n in numbers]


def _exists_in_room(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """Is there a {colour} {category} in the {room}? Yes about a visible object, else a near miss."""
    present = {(o.colour, o.category, o.room) for o in facts.home.objects}
    rooms = sorted(nameable_rooms(facts.home))
    visible = sorted({(o.colour, o.category, o.room) for o in facts.visible_objects() if o.room in rooms})
    if not visible:
        return None
    if rng.random() < 0.5:
        colour, category, room = _pick(rng, visible)
        answer = "Yes"
    else:
        for _ in range(100):  # a near miss: a real object with its colour or its room changed
            colour, category, room = _pick(rng, visible)
            if rng.random() < 0.5:
                colour = _pick(rng, list(COLOURS))
            else:
                room = _pick(rng, rooms)
            if (colour, category, room) not in present:
                break
        else:
            return None
        answer = "No"
    return {"colour": colour, "category": category, "room": room}, answer, _padded(YES_NO)


def _exists_in_storage(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """Is there any {category} in the {container} in the {room}? (closed storage: act to know)"""
    options = _unique_storage(facts, closed=True)
    if not options:
        return None
    storage = _pick(rng, options)
    inside = {o.category for o in facts.home.objects if facts.storage_of(o) is storage}
    if inside and rng.random() < 0.5:
        category, answer = _pick(rng, sorted(inside)), "Yes"
    else:
        category, answer = _pick(rng, sorted(set(OBJECTS) - inside)), "No"
    return {"category": category, "container": storage.category, "room": storage.room}, answer, _padded(YES_NO)


def _power_state(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """Is the {appliance} in the {room} on or off?"""
    counts = Counter((f.room, f.category) for f in facts.appliances())
    rooms = nameable_rooms(facts.home)
    options = [f for f in facts.appliances() if f.room in rooms and counts[(f.room, f.category)] == 1]
    if not options:
        return None
    appliance = _pick(rng, options)
    answer = "On" if appliance.state["power"] == "on" else "Off"
    return {"appliance": appliance.category, "room": appliance.room}, answer, _padded(ON_OFF)


def _door_state(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """Is the {container} in the {room} open or closed?"""
    options = _unique_storage(facts, closed=True) + _unique_storage(facts, closed=False)
    if not options:
        return None
    storage = _pick(rng, sorted(options, key=lambda f: f.instance_id))
    answer = "Open" if facts.is_open(storage) else "Closed"
    return {"container": storage.category, "room": storage.room}, answer, _padded(OPEN_CLOSED)


def _room_of_object(rng: np.random.Generator, facts: HomeFacts) -> Draw | None:
    """Which room is the {colour} {category} in? (one such object in the home, visible, in a
    nameable room; the other choices are other kinds, those of the home first)"""
    item = _unique_visible(rng, facts, ("colour", "category"), facts.home.objects)
    if item is None:
        return None
    here = [r.kind for r in facts.home.rooms]
    return {"colour": item.colour, "category": item.category}, item.room, _shuffled(
        rng, item.room, _words_but(rng, list(ROOM_TYPES), item.room, preferred=here))


#: How to draw each template's question, by the template's text.
_DRAWERS: dict[str, Callable[[np.random.Generator, HomeFacts], Draw | None]] = {
    "Which object in the {room} is {colour}?": _object_colour_in_room,
    "What colour is the {category} in the {room}?": _colour_of_object,
    "What is inside the {container} in the {room}?": _inside_storage,
    "How many {plural} are there in the {room}?": _count_in_room,
    "Is there a {colour} {category} in the {room}?": _exists_in_room,
    "Is there any {category} in the {container} in the {room}?": _exists_in_storage,
    "Is the {appliance} in the {room} on or off?": _power_state,
    "Is the {container} in the {room} open or closed?": _door_state,
    "Which room is the {colour} {category} in?": _room_of_object,
}


def start_pose(home: HomeSpec, rng: np.random.Generator) -> tuple[float, float, float]:
    """A pose in the home's connected free space, at least `START_CLEARANCE` from any obstacle.

    Args:
        home: the home.
        rng: the draws' generator.

    Returns:
        The pose (x, y, yaw).

    Raises:
        RuntimeError: no spot is that clear.
    """
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
