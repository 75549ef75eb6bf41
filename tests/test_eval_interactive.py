"""`homebot eval interactive`: Table I rows per task, appended per scene and resumed; any seeds, the
fixed splits, and the failures counted by cause."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from agent.app.eval.failure_causes import NOT_RECOVERED, OTHER, PERCEPTION, action_cause, cause_table
from agent.app.eval.interactive import COLUMNS, evaluate_interactive, split_seeds
from skills.robot_picks import beyond_reach
from worlds.tabletop import tabletop_variant
from worlds.tabletop_splits import SPLITS


def test_rows_per_task_and_a_rerun_redoes_nothing(tmp_path: Path) -> None:
    seen: list[dict] = []
    report = evaluate_interactive(tmp_path, ["occlusion", "recursive"], 2, "symbolic",
                                  lambda done, total, row: seen.append(row))
    assert report["n"] == 4 and len(seen) == 4
    assert set(report["table"]) == {"occlusion", "recursive"}
    for row in report["table"].values():
        assert set(row) == set(COLUMNS)
        assert row["success"] == (1.0, 0.0) and row["graph_edit_distance"] == (0.0, 0.0)
    lines = (tmp_path / "interactive-results.jsonl").read_text().splitlines()
    seen.clear()
    again = evaluate_interactive(tmp_path, ["occlusion", "recursive"], 2, "symbolic",
                                 lambda done, total, row: seen.append(row))
    assert not seen and again["table"] == report["table"]
    assert (tmp_path / "interactive-results.jsonl").read_text().splitlines() == lines


@pytest.mark.parametrize("tasks, variants, executor, problem", [
    (["shelves"], 1, "symbolic", "--tasks: unknown shelves"),
    (["occlusion"], 0, "symbolic", "--variants: 0"),
    (["occlusion"], 1, "telepathic", "--executor: 'telepathic'"),
])
def test_bad_options_are_named(tmp_path: Path, tasks, variants, executor, problem) -> None:
    with pytest.raises(ValueError, match=problem):
        evaluate_interactive(tmp_path, tasks, variants, executor)


def test_any_seed_base_runs_its_own_variants(tmp_path: Path) -> None:
    report = evaluate_interactive(tmp_path, ["door-only"], 2, "symbolic", seed_base=5_000)
    lines = (tmp_path / "interactive-results.jsonl").read_text().splitlines()
    seeds = sorted(json.loads(line)["seed"] for line in lines)
    assert seeds == [5_000, 5_001] and report["seeds"] == [5_000, 5_001] and report["n"] == 2
    kept = json.loads((tmp_path / "interactive-report.json").read_text())
    assert kept["seeds"] == [5_000, 5_001] and kept["causes"] == {} and set(kept["table"]) == {"door-only"}
    # and the variants differ from the tuning seeds' (a variant is its seed, whatever the number)
    assert tabletop_variant("door-only", 5_000) != tabletop_variant("door-only", 0)


def test_the_splits_are_fixed_and_apart() -> None:
    tuning, wide, reported = SPLITS["tuning"].seeds(), SPLITS["tuning-wide"].seeds(), SPLITS["reported"].seeds()
    assert (tuning.start, len(tuning)) == (0, 10) and len(reported) == 30
    assert not set(reported) & (set(tuning) | set(wide))
    assert split_seeds("reported", None, None) == (10_000, 30)
    assert split_seeds("reported", 12, None) == (10_000, 12)  # the first few, evenly per task
    assert split_seeds(None, None, None) == (0, 10)
    assert split_seeds(None, 100, 1_000) == (1_000, 100)


@pytest.mark.parametrize("split, variants, seed_base, record, problem", [
    ("holdout", None, None, False, "--split: 'holdout'"),
    ("reported", None, 3, False, "--seed-base: the reported split starts at 10000"),
    ("reported", 31, None, False, "--variants: 31 must be 1..30"),
    ("reported", None, None, True, "--record: the reported split"),
    (None, 5, 9_998, False, "--seed-base: seeds 9998..10002 reach into the reported split"),
    (None, 0, None, False, "--variants: 0"),
])
def test_split_options_that_conflict_are_named(split, variants, seed_base, record, problem) -> None:
    with pytest.raises(ValueError, match=problem):
        split_seeds(split, variants, seed_base, record)


@pytest.mark.parametrize("reason, cause", [
    ("the arm stopped 0.041 rad short of its target: something held it back (a touch too light for the world "
     "to report as a contact)", "light touch"),
    ("the arm stopped 0.104 rad short of its target: held back against handle 12 (panda_leftfinger)",
     "held back against a contact"),
    ("stopped on contact with bowl 14 (panda_hand)", "contact stop"),
    ("IK: above unreachable: did not converge: best error 15.0 cm / 3.1 deg", "IK no solution"),
    ("idle spot: no free place 0.28 m across on the surface at 0.750 m", "no idle space"),
    ("pick: no route clear of what stands near, and none is taken unchecked under a board close over the "
     "object or its place", "no clear route in storage"),
    ("pick_away: plan: pick: no route clear of what stands near, and none is taken unchecked under a board "
     "close over the object or its place" + beyond_reach(np.array([0.1, 0.25, 0.9]), (0.1, -0.72)),
     "beyond the arm's reach"),
    ("pick_away: plan: pick: no room to lift it: what stands over it is 0.062 m over its top, and it is lifted "
     "0.156 m at the least, clear of its own height (of what it may cover)"
     + beyond_reach(np.array([0.1, 0.25, 0.9]), (0.1, -0.72)), "no room to lift it in storage"),
    ("pick: no route clear of what stands near, and every route taken unchecked that reaches would carry it "
     "through what stands near", "carry would meet what stands near"),
    ("the base could not reach (0.12, -0.80, 90°): it touched door", "base unreachable"),
    ("door 7 has no handle the robot has seen", "no handle points"),
    ("the gripper closed on nothing (0 mm between the fingers)", "grasp closed on nothing"),
    ("the door did not open: its handle went 0.100 rad of the 1.300 rad planned", "part held back"),
    ("a reason no rule knows", OTHER),
])
def test_a_failed_action_is_put_in_its_cause(reason: str, cause: str) -> None:
    assert action_cause(f"pick_away cup (o12) FAILED: {reason}") == ("pick_away", cause)


def test_a_pick_beyond_the_arms_reach_says_how_far_out_its_object_stands() -> None:
    assert beyond_reach(np.array([0.1, 0.25, 0.9]), (0.1, -0.72)) == (
        " (0.97 m from the base's axis, beyond the arm's reach over a table, 0.85 m)")
    assert beyond_reach(np.array([0.5, 0.05, 0.9]), (0.1, -0.72)) == (
        " (0.87 m from the base's axis, beyond the arm's reach over a table, 0.85 m)")  # aside as well as out
    assert beyond_reach(np.array([0.1, 0.1, 0.9]), (0.1, -0.72)) == ""  # 0.82 m: within it


def test_the_cause_table_counts_actions_and_failed_scenes() -> None:
    rows = [
        {"task": "drawer-only", "success": 0.0, "state_recovered": 1.0, "failed_actions": []},  # perception
        {"task": "drawer-only", "success": 1.0, "state_recovered": 1.0, "failed_actions": []},  # nothing failed
        {"task": "occlusion", "success": 0.0, "state_recovered": 0.0, "failed_actions": [
            "pick_back jar (o9) FAILED: stopped on contact with drawer 4 (panda_leftfinger)",
            "pick_back jar (o9) FAILED: stopped on contact with drawer 4 (panda_hand)"]},
        {"task": "recursive", "success": 1.0, "state_recovered": 1.0, "failed_actions": [  # recovered from it
            "open_door door (o3) FAILED: stopped on contact with bowl 5 (panda_hand)"]},
        {"task": "door-only", "success": 0.0, "state_recovered": 1.0},  # the symbolic executor's row
    ]
    table = cause_table(rows)
    assert list(table) == [PERCEPTION, "contact stop", NOT_RECOVERED]
    perception, contact, recovered = table[PERCEPTION], table["contact stop"], table[NOT_RECOVERED]
    assert (perception.scenes, perception.actions, dict(perception.tasks)) == (2, 0, {"drawer-only": 1, "door-only": 1})
    assert (contact.actions, contact.scenes) == (3, 1)
    assert dict(contact.primitives) == {"pick_back": 2, "open_door": 1} and dict(contact.tasks) == {"occlusion": 1}
    assert (recovered.scenes, dict(recovered.tasks)) == (1, {"occlusion": 1})


def test_the_command_runs_a_seed_range_and_prints_the_causes(tmp_path: Path, capsys) -> None:
    from agent.app.cli import main

    assert main(["eval", "interactive", "--tasks", "recursive", "--variants", "1", "--seed-base", "1000",
                 "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "1 scenes (seeds 1000-1000)" in printed and "failures by cause\nno failures" in printed
    assert main(["eval", "interactive", "--split", "reported", "--seed-base", "4", "--out", str(tmp_path)]) == 2
    assert "--seed-base: the reported split starts at 10000" in capsys.readouterr().err
