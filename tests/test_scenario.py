"""Scenarios: unambiguous questions that parse back to their target, true answers, clear start poses."""

from __future__ import annotations

import math
from collections import Counter

import pytest

from worlds.freespace import clearance
from worlds.home import HomeSpec, generate_home
from worlds.scenario import START_CLEARANCE, Scenario, make_scenario
from worlds.vocabulary import LETTERS, PAD_CHOICE, parse_question

SEEDS = range(80)


@pytest.fixture(scope="module")
def cases() -> list[tuple[HomeSpec, Scenario]]:
    out = []
    for seed in SEEDS:
        home = generate_home(seed)
        out.append((home, make_scenario(home, seed)))
    return out


def _true_answer(home: HomeSpec, scenario: Scenario) -> str:
    """What the home says the answer is, worked out independently of the generator."""
    t = scenario.target
    if scenario.asks == "yes/no":
        present = any((o.colour, o.category, o.room) == (t["colour"], t["category"], t["room"]) for o in home.objects)
        return "Yes" if present else "No"
    if scenario.asks == "category":
        matches = [o for o in home.objects if o.room == t["room"] and o.colour == t["colour"]]
        matches += [f for f in home.furniture if f.room == t["room"] and f.colour == t["colour"]]
    elif scenario.asks == "colour":
        matches = [o for o in home.objects if o.room == t["room"] and o.category == t["category"]]
    else:
        matches = [o for o in home.objects if o.colour == t["colour"] and o.category == t["category"]]
    assert len(matches) == 1, f"ambiguous question {scenario.question!r}: {matches}"
    return getattr(matches[0], scenario.asks)


def test_question_parses_back_to_its_target(cases: list[tuple[HomeSpec, Scenario]]) -> None:
    for _, scenario in cases:
        parsed = parse_question(scenario.question)
        assert parsed is not None, scenario.question
        assert parsed.template.kind == scenario.kind and parsed.template.asks == scenario.asks
        assert {"category": parsed.category, "colour": parsed.colour, "room": parsed.room} == scenario.target


def test_answer_letter_points_at_the_true_answer(cases: list[tuple[HomeSpec, Scenario]]) -> None:
    for home, scenario in cases:
        truth = _true_answer(home, scenario)
        assert scenario.answer in LETTERS
        assert scenario.choices[LETTERS.index(scenario.answer)] == truth == scenario.answer_text
        real = [c for c in scenario.choices if c != PAD_CHOICE]
        assert len(scenario.choices) == 4 and len(set(real)) == len(real)
        if scenario.asks == "yes/no":
            assert scenario.choices == ("Yes", "No", PAD_CHOICE, PAD_CHOICE)
        else:
            assert len(real) == 4


def test_every_template_is_used_and_existence_is_yes_and_no(cases: list[tuple[HomeSpec, Scenario]]) -> None:
    assert {s.asks for _, s in cases} == {"category", "colour", "room", "yes/no"}
    existence = Counter(s.answer_text for _, s in cases if s.asks == "yes/no")
    assert existence["Yes"] >= 3 and existence["No"] >= 3
    assert len(Counter(s.answer for _, s in cases if s.asks != "yes/no")) == 4


def test_start_pose_is_clear_and_inside(cases: list[tuple[HomeSpec, Scenario]]) -> None:
    for home, scenario in cases:
        x, y, yaw = scenario.start_pose
        assert clearance(home, x, y) >= START_CLEARANCE
        assert home.room_at(x, y) is not None
        assert -math.pi <= yaw <= math.pi


def test_budget_follows_the_paper(cases: list[tuple[HomeSpec, Scenario]]) -> None:
    for home, scenario in cases:
        assert scenario.budget == int(3 * math.sqrt(home.area_m2))


def test_same_seed_same_scenario_and_dict_round_trip() -> None:
    home = generate_home(21)
    first, second = make_scenario(home, 21), make_scenario(home, 21)
    assert first == second
    assert Scenario.from_dict(first.to_dict()) == first
    others = {make_scenario(generate_home(seed), seed).question for seed in range(10)}
    assert len(others) > 5
