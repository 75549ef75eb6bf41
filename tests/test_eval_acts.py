"""The act branch's figures over an evaluation's results file."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from agent.eqa.stopping import BudgetRule
from agent.app.cli import main
from agent.app.eval.acts import cause, format_summary, summarise


def _act(looked: bool, closed: bool | None, stage: str | None = None, reason: str = "") -> dict:
    return {"storage": "cabinet", "part": "door 7", "opened": looked and stage is None, "looked": looked,
            "closed": closed, "stage": stage, "reason": reason}


def _step(step: int, best: str, relevance: float) -> dict:
    return {"step": step, "answer_probs": {letter: 0.7 if letter == best else 0.1 for letter in "ABCD"},
            "relevance": relevance}


RESULTS = [
    {"id": "a", "variant": "semantic", "status": "answered", "answer": "A", "ground_truth": "A", "budget": 3,
     "step_scores": [_step(1, "B", 0.3), _step(2, "A", 0.9), _step(3, "B", 0.2)],
     "acts": [{**_act(True, True), "step": 2}]},
    {"id": "b", "variant": "semantic", "status": "answered", "answer": "B", "ground_truth": "A",
     "acts": [_act(False, None, "open", "the base could not reach (1.00, 2.00, 90°): it touched wall"),
              _act(True, False, "close", "close_door: grasp the door handle: the gripper closed on nothing (0 mm)")]},
    {"id": "c", "variant": "semantic", "status": "answered", "answer": "C", "ground_truth": "C", "acts": []},
    {"id": "c", "variant": "fbe", "status": "answered", "answer": "D", "ground_truth": "C", "acts": []},
    {"id": "d", "variant": "semantic", "status": "failed", "reason": "no world", "acts": []},
]


@pytest.mark.parametrize("reason, name", [
    ("stand: no place to open the door from (3 unreachable)", "no stand clear of the opening within reach"),
    ("open_door: pull the door open: the door did not open: its handle went 0.314 rad", "the part was held back"),
    ("open_door: approach the door handle: stopped on contact with handle 114", "the arm touched something"),
    ("plan: IK: grasp pose of door handle unreachable", "out of the arm's reach"),
    ("something new", "other"),
])
def test_a_failure_s_cause_is_read_off_its_reason(reason: str, name: str) -> None:
    assert cause(reason) == name


def test_episodes_and_acts_are_counted_for_one_method() -> None:
    summary = summarise(RESULTS, "semantic")
    assert (summary.episodes, summary.correct, summary.episodes_acting, summary.episodes_looked) == (3, 2, 2, 2)
    assert summary.correct_looked == 1
    assert (summary.acts, summary.opened, summary.looked, summary.closed, summary.left_open) == (3, 1, 2, 1, 1)
    assert summary.failures == {("open", "the base was blocked on its way"): 1,
                                ("close", "the grasp missed the handle"): 1}
    assert (summary.inside_views, summary.inside_right) == (1, 1)  # the view inside backed A, the truth
    assert "acts: closed again             1/2 (50 %)" in format_summary(summary)


def test_what_a_stopping_rule_would_have_answered_is_replayed_over_the_recorded_steps() -> None:
    summary = summarise(RESULTS, "semantic", BudgetRule)  # to the budget: argmax f̂ at the most relevant step
    assert summary.correct_stopping == 1  # episode a; the others recorded no steps


def test_the_summary_is_printed_from_a_results_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "explore-results.jsonl"
    path.write_text("".join(json.dumps(r) + "\n" for r in RESULTS))
    assert main(["eval", "acts", str(path), "--method", "semantic"]) == 0
    out = capsys.readouterr().out
    assert "episodes answered right        2/3 (67 %) at the full budget, 1/3 (33 %) stopped by the stopping rule" in out
    assert main(["eval", "acts", str(tmp_path / "missing.jsonl")]) == 2


def test_the_parts_of_one_piece_opened_in_one_act_count_as_one_view_inside() -> None:
    both_doors = {"id": "e", "variant": "semantic", "status": "answered", "answer": "A", "ground_truth": "A",
                  "budget": 2, "step_scores": [_step(1, "B", 0.3), _step(2, "A", 0.9)],
                  "acts": [{**_act(True, True), "step": 2}, {**_act(True, True), "part": "door 9", "step": 2}]}
    summary = summarise([both_doors])
    assert (summary.acts, summary.looked) == (2, 2)
    assert (summary.inside_views, summary.inside_right) == (1, 1)
