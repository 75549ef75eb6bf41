"""Success against normalised time, computed from per-step scores."""

from __future__ import annotations

import numpy as np

from agent.eval.curves import answer_after, success_at, success_curves


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
    assert curves["m"].tolist() == [0.5, 0.5]
