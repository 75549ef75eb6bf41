"""Scenarios: unambiguous questions whose answers follow from the home, in the paper's proportions."""

from __future__ import annotations

import math
from collections import Counter

import pytest

from worlds.facts import HomeFacts
from worlds.freespace import clearance
from worlds.home import HomeSpec, generate_home
from worlds.questions import CATEGORY_SHARES, parse_question
from worlds.scenario import START_CLEARANCE, Scenario, make_scenario
from worlds.vocabulary import ROOM_TYPES, room_kind
from worlds.bus.questions import LETTERS, PAD_CHOICE

SEEDS = range(120)


@pytest.fixture(scope="module")
def cases() -> list[tuple[HomeSpec, Scenario]]:
    return [(home, make_scenario(home, seed)) for seed in SEEDS for home in [generate_home(seed)]]


@pytest.fixture(scope="module")
def hidden_cases() -> list[tuple[HomeSpec, Scenario]]:
    return [(home, make_scenario(home, seed, hidden=True)) for seed in range(40) for home in [generate_home(seed)]]


def _true_answer(home: HomeSpec, scenario: Scenario) -> str:
    """What the home says the answer is, worked out from the spec, apart from the generator."""
    t, facts = scenario.target, HomeFacts(home)
    objects = home.objects
    if scenario.asks == "count":
        return str(sum(o.room == t["room"] and o.category == t["category"] for o in objects))
    if scenario.asks in ("power", "door"):
        wanted = t["appliance"] or t["container"]
        [thing] = [f for f in home.furniture if f.room == t["room"] and f.category == wanted]
        if scenario.asks == "power":
            return thing.state["power"].capitalize()
        return "Open" if facts.is_open(thing) else "Closed"
    if t["container"] is not None:
        [storage] = [f for f in home.furniture if f.room == t["room"] and f.category == t["container"]]
        inside = [o for o in objects if facts.storage_of(o) == storage]
        if scenario.asks == "yes/no":
            return "Yes" if any(o.category == t["category"] for o in inside) else "No"
        [item] = inside
        return item.category
    if scenario.asks == "yes/no":
        present = any((o.colour, o.category, o.room) == (t["colour"], t["category"], t["room"]) for o in objects)
        return "Yes" if present else "No"
    if scenario.asks == "category":
        matches = [o for o in objects if o.room == t["room"] and o.colour == t["colour"]]
        matches += [f for f in home.furniture if f.room == t["room"] and f.colour == t["colour"]]
    elif scenario.asks == "colour":
        matches = [o for o in objects if o.room == t["room"] and o.category == t["category"]]
    else:
        matches = [o for o in objects if o.colour == t["colour"] and o.category == t["category"]]
    assert len(matches) == 1, f"ambiguous question {scenario.question!r}: {matches}"
    return getattr(matches[0], scenario.asks)


def test_question_parses_back_to_its_target(cases, hidden_cases) -> None:
    for _, scenario in cases + hidden_cases:
        parsed = parse_question(scenario.question)
        assert parsed is not None, scenario.question
        assert parsed.template.kind == scenario.kind and parsed.template.asks == scenario.asks
        named = {k: getattr(parsed, k) for k in ("category", "colour", "room", "container", "appliance")}
        assert named == scenario.target


def test_every_answer_follows_from_the_home(cases, hidden_cases) -> None:
    for home, scenario in cases + hidden_cases:
        truth = _true_answer(home, scenario)
        assert scenario.choices[LETTERS.index(scenario.answer)] == truth == scenario.answer_text, scenario.question
        real = [c for c in scenario.choices if c != PAD_CHOICE]
        assert len(scenario.choices) == 4 and len(set(real)) == len(real) >= 2


def test_questions_that_are_not_hidden_ask_only_about_what_can_be_seen(cases) -> None:
    for home, scenario in cases:
        facts, t = HomeFacts(home), scenario.target
        if scenario.asks in ("category", "colour", "room") and t["container"] is None:
            match = [o for o in home.objects if all(t[k] in (None, getattr(o, k)) for k in ("category", "colour", "room"))
                     and getattr(o, scenario.asks) == scenario.answer_text]
            assert match and not any(facts.is_hidden(o) for o in match), scenario.question


def test_hidden_questions_ask_about_closed_storage(hidden_cases) -> None:
    for home, scenario in hidden_cases:
        facts = HomeFacts(home)
        [storage] = [f for f in home.furniture if f.room == scenario.target["room"] and f.category == scenario.target["container"]]
        assert storage.storage is not None and not facts.is_open(storage), scenario.question
    answers = Counter(s.answer_text for _, s in hidden_cases if s.asks == "yes/no")
    assert answers["Yes"] >= 3 and answers["No"] >= 3


def test_questions_name_only_rooms_a_camera_can_pick_out(cases, hidden_cases) -> None:
    """A camera tells a bedroom by its bed, never the first bedroom from the second: a question
    names only rooms whose kind the home has once, by that kind, and room choices differ in kind."""
    asked_in_homes_with_repeats = 0
    for home, scenario in cases + hidden_cases:
        kinds = Counter(room.kind for room in home.rooms)
        asked_in_homes_with_repeats += max(kinds.values()) > 1
        named = scenario.target["room"] or (scenario.answer_text if scenario.asks == "room" else None)
        if named is not None:
            [room] = [r for r in home.rooms if r.name == named]
            assert kinds[room.kind] == 1 and room.name == room.kind, scenario.question
        if scenario.asks == "room":
            assert len({room_kind(c) for c in scenario.choices}) == 4 and all(c in ROOM_TYPES for c in scenario.choices)
    assert asked_in_homes_with_repeats >= 20  # homes with a second bedroom still get questions


def test_categories_come_in_about_the_papers_proportions(cases) -> None:
    shares = Counter(s.kind for _, s in cases)
    for kind, share in CATEGORY_SHARES.items():
        assert abs(shares[kind] / len(cases) - share) < 0.1, (kind, shares)
    assert len(Counter(s.answer for _, s in cases)) == 4


def test_start_pose_is_clear_and_inside(cases) -> None:
    for home, scenario in cases:
        x, y, yaw = scenario.start_pose
        assert clearance(home, x, y) >= START_CLEARANCE
        assert home.room_at(x, y) is not None
        assert -math.pi <= yaw <= math.pi


def test_budget_follows_the_paper(cases) -> None:
    for home, scenario in cases:
        assert scenario.budget == int(3 * math.sqrt(home.area_m2))


def test_same_seed_same_scenario_and_dict_round_trip() -> None:
    home = generate_home(21)
    first, second = make_scenario(home, 21), make_scenario(home, 21)
    assert first == second
    assert Scenario.from_dict(first.to_dict()) == first
    assert len({make_scenario(generate_home(seed), seed).question for seed in range(10)}) > 5


def test_impossible_requests_are_refused() -> None:
    with pytest.raises(ValueError, match="no question template"):
        make_scenario(generate_home(1), 1, kinds=("counting",), hidden=True)
