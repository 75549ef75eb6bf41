"""Success, target seen and coverage against normalised time, from per-step scores and the world's reports."""

from __future__ import annotations

import numpy as np

from pathlib import Path

from agent.app.eval.curves import (answer_after, coverage_at, coverage_curves, explore_panels, rooms_entered_at,
                               success_at, success_curves, target_seen_at, target_seen_curves, write_curves_csv)


def _steps(*rows: tuple[str, float]) -> list[dict]:
    """Steps whose f̂ puts 0.9 on the given letter, with the given relevance."""
    return [{"step": i + 1, "answer_probs": {l: (0.9 if l == best else 0.1 / 3) for l in "ABCD"}, "relevance": rel}
            for i, (best, rel) in enumerate(rows)]


def test_the_answer_after_k_steps_comes_from_the_most_relevant_of_them() -> None:
    steps = _steps(("A", 0.2), ("B", 0.9), ("C", 0.5))
    assert answer_after(steps, 1) == "A"
    assert answer_after(steps, 2) == "B"
    assert answer_after(steps, 3) == "B"
    assert answer_after(steps, 0) is None


def test_success_follows_normalised_time_and_a_short_episode_keeps_its_last_answer() -> None:
    result = {"budget": 4, "ground_truth": "B", "step_scores": _steps(("A", 0.2), ("B", 0.9))}
    taus = np.array([0.25, 0.5, 0.75, 1.0])
    assert success_at(result, taus).tolist() == [0.0, 1.0, 1.0, 1.0]


def test_curves_average_per_method() -> None:
    right = {"method": "m", "budget": 2, "ground_truth": "A", "step_scores": _steps(("A", 0.5), ("A", 0.5))}
    wrong = {"method": "m", "budget": 2, "ground_truth": "B", "step_scores": _steps(("A", 0.5), ("A", 0.5))}
    failed = {"method": "m", "budget": 2, "ground_truth": "A", "step_scores": []}
    curves = success_curves([right, wrong, failed], np.array([0.5, 1.0]))
    assert curves.by_method["m"].tolist() == [0.5, 0.5]
    assert curves.counts == {"m": 2}


def _seen(method: str, first_step: int | None, steps: int = 4) -> dict:
    """A full-budget episode (budget 4) whose world report says the target was first in head frame
    ``first_step`` (None: never), with 10 m² more of 40 m² floor seen and one more room every frame."""
    seen = None if first_step is None else {"step": first_step, "share": 0.01, "base_pose": [0, 0, 0]}
    return {"method": method, "budget": 4, "ground_truth": "A", "step_scores": _steps(*[("A", 0.5)] * steps),
            "evaluation": {"target_seen": seen, "free_floor_m2": 40.0,
                           "floor_seen_by_frame": [10.0 * (i + 1) for i in range(steps)],
                           "rooms_entered_by_frame": [i + 1 for i in range(steps)]}}


def test_the_target_counts_as_seen_once_the_frame_that_showed_it_has_been_taken() -> None:
    taus = np.array([0.25, 0.5, 0.75, 1.0])  # 1, 2, 3, 4 steps: frames 0, 0-1, 0-2, 0-3
    assert target_seen_at(_seen("m", 0), taus).tolist() == [1.0, 1.0, 1.0, 1.0]
    assert target_seen_at(_seen("m", 2), taus).tolist() == [0.0, 0.0, 1.0, 1.0]
    assert target_seen_at(_seen("m", None), taus).tolist() == [0.0, 0.0, 0.0, 0.0]


def test_target_seen_rates_leave_out_episodes_without_a_report() -> None:
    unreported = {**_seen("m", 0), "evaluation": None}
    failed = {**_seen("m", 0), "step_scores": []}
    rates = target_seen_curves([_seen("m", 0), _seen("m", 3), unreported, failed, _seen("n", None)],
                               np.array([0.5, 1.0]))
    assert rates.counts == {"m": 2, "n": 1}
    assert rates.by_method["m"].tolist() == [0.5, 1.0] and rates.by_method["n"].tolist() == [0.0, 0.0]


def test_coverage_and_rooms_follow_the_frames_taken_and_a_short_episode_keeps_its_last() -> None:
    taus = np.array([0.25, 0.5, 0.75, 1.0])
    assert coverage_at(_seen("m", 0), taus).tolist() == [0.25, 0.5, 0.75, 1.0]
    assert rooms_entered_at(_seen("m", 0), taus).tolist() == [1, 2, 3, 4]
    short = _seen("m", 0, steps=2)
    assert coverage_at(short, taus).tolist() == [0.25, 0.5, 0.5, 0.5]
    old_file = {**_seen("m", 0), "evaluation": {"target_seen": None}}  # a report without the progress
    assert coverage_curves([old_file, _seen("m", 0)], taus).counts == {"m": 1}


def test_the_csv_has_success_columns_then_the_reports_columns(tmp_path: Path) -> None:
    results = [_seen("fbe", 1), _seen("semantic", None, steps=2)]
    taus = np.array([0.5, 1.0])
    write_curves_csv(tmp_path / "curves.csv", explore_panels(results, "t", taus), taus)
    lines = (tmp_path / "curves.csv").read_text().splitlines()
    assert lines[0] == ("normalised_time,fbe (n=1),semantic (n=1),"
                        "fbe target seen (n=1),semantic target seen (n=1),"
                        "fbe floor seen (n=1),semantic floor seen (n=1),"
                        "fbe rooms entered (n=1),semantic rooms entered (n=1)")
    assert lines[1:] == ["0.50,1.0000,1.0000,1.0000,0.0000,0.5000,0.5000,2.0000,2.0000",
                         "1.00,1.0000,1.0000,1.0000,0.0000,1.0000,0.5000,4.0000,2.0000"]
