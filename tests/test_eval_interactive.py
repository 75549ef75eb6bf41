"""`homebot eval interactive`: Table I rows per task, appended per scene and resumed."""

from __future__ import annotations

from pathlib import Path

import pytest

from agent.app.eval.interactive import COLUMNS, evaluate_interactive


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
    (["occlusion"], 11, "symbolic", "--variants: 11"),
    (["occlusion"], 1, "telepathic", "--executor: 'telepathic'"),
])
def test_bad_options_are_named(tmp_path: Path, tasks, variants, executor, problem) -> None:
    with pytest.raises(ValueError, match=problem):
        evaluate_interactive(tmp_path, tasks, variants, executor)
