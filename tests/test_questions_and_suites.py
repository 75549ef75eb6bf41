"""Question templates read back to their slots; suites are seeded, split, appended and resumed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from worlds.questions import CATEGORY_SHARES, TEMPLATES, format_question, parse_question, plural
from worlds.suite import SuiteError, plan_split, read_suite, write_suite

SLOTS = {"category": "mug", "colour": "red", "room": "second bedroom", "container": "fridge", "appliance": "lamp"}


@pytest.mark.parametrize("template", TEMPLATES, ids=lambda t: t.text)
def test_every_template_reads_back_to_its_slots(template) -> None:
    text = format_question(template, **SLOTS)
    parsed = parse_question(text)
    assert parsed is not None and parsed.template == template
    for slot in ("category", "colour", "room", "container", "appliance"):
        named = "{" + slot + "}" in template.text or (slot == "category" and "{plural}" in template.text)
        assert getattr(parsed, slot) == (SLOTS[slot] if named else None), slot


def test_plurals_and_category_shares() -> None:
    assert [plural(w) for w in ("mug", "box", "toothbrush", "story", "key")] == ["mugs", "boxes", "toothbrushes", "stories", "keys"]
    assert sum(CATEGORY_SHARES.values()) == pytest.approx(1.0, abs=1e-9)
    assert {t.kind for t in TEMPLATES} == set(CATEGORY_SHARES)


def test_questions_outside_the_templates_are_not_understood() -> None:
    assert parse_question("What is the meaning of life?") is None
    assert parse_question("Which room is the red unicorn in?") is None


def test_split_plans_consecutive_seed_ranges_and_rejects_bad_sizes() -> None:
    parts = plan_split(5, [3, 2], seed_base=10)
    assert [(p.name, list(p.seeds)) for p in parts] == [("calib", [10, 11, 12]), ("test", [13, 14])]
    for n, split in ((5, [3, 3]), (5, [5, 0]), (0, [])):
        with pytest.raises(SuiteError, match="split|n:"):
            plan_split(n, split, 0)


def test_suites_are_the_same_for_the_same_seeds(tmp_path: Path) -> None:
    first = write_suite(tmp_path / "a", plan_split(4, [2, 2], 0))
    second = write_suite(tmp_path / "b", plan_split(4, [2, 2], 0))
    for name in ("calib", "test"):
        assert first[name].read_text() == second[name].read_text()
    entries = read_suite(first["calib"])
    assert [e["id"] for e in entries] == ["calib-0000", "calib-0001"]
    assert all(parse_question(e["scenario"]["question"]) for e in entries)


def test_an_interrupted_suite_resumes_without_redoing_lines(tmp_path: Path) -> None:
    whole = write_suite(tmp_path / "whole", plan_split(4, [4], 0, ("suite",)))["suite"].read_text().splitlines()
    path = tmp_path / "cut" / "suite.jsonl"
    path.parent.mkdir()
    path.write_text("\n".join(whole[:2]) + "\n" + whole[2][:40])  # two lines, then a torn third
    seen: list[int] = []
    write_suite(path.parent, plan_split(4, [4], 0, ("suite",)), lambda part, done, total: seen.append(done))
    assert path.read_text().splitlines() == whole
    assert seen[-1] == 4


def test_a_torn_last_line_is_dropped_and_a_bad_line_is_named(tmp_path: Path) -> None:
    whole = write_suite(tmp_path, plan_split(2, [2], 0, ("suite",)))["suite"]
    lines = whole.read_text().splitlines()
    whole.write_text(lines[0] + "\n" + lines[1][:30])
    assert len(read_suite(whole)) == 1
    bad = json.loads(lines[0])
    bad["seed"] = "seven"
    whole.write_text(json.dumps(bad) + "\n" + lines[1] + "\n")
    with pytest.raises(SuiteError, match=r"suite.jsonl:1: seed"):
        read_suite(whole)
