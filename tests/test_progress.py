"""The progress line of long runs: rewritten in place on a terminal, whole lines in a log."""

from __future__ import annotations

import io

import pytest

from agent.app.eval.interactive import scene_progress
from agent.app.progress import ProgressLine


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_a_terminal_sees_one_line_rewritten_and_ended_at_the_last_update() -> None:
    out = Terminal()
    line = ProgressLine(out)
    line.show("1/3 scenes")
    line.show("2/3 scenes")
    line.show("3/3 scenes", last=True)
    assert out.getvalue() == "\r  1/3 scenes   \r  2/3 scenes   \r  3/3 scenes   \n"


def test_a_log_gets_whole_lines_no_more_often_than_asked_and_always_the_last() -> None:
    out = io.StringIO()
    line = ProgressLine(out, every_s=3600.0)
    for done in range(1, 5):
        line.show(f"{done}/5 scenes")
    line.show("5/5 scenes", last=True)
    assert "\r" not in out.getvalue()
    assert out.getvalue().splitlines() == ["  1/5 scenes", "  5/5 scenes"]
    every = io.StringIO()
    line = ProgressLine(every, every_s=0.0)
    for done in range(1, 4):
        line.show(f"{done}/3 scenes", last=done == 3)
    assert every.getvalue().splitlines() == ["  1/3 scenes", "  2/3 scenes", "  3/3 scenes"]


def test_the_evaluation_writes_to_stderr_as_it_is_when_each_scene_ends(monkeypatch: pytest.MonkeyPatch) -> None:
    """Written to wherever stderr points at the time (a log the run was redirected to)."""
    progress = scene_progress()
    log = io.StringIO()
    monkeypatch.setattr("sys.stderr", log)
    progress(1, 2, {"task": "drawer-only", "seed": 0, "success": True, "graph_edit_distance": 0.0})
    progress(2, 2, {"task": "recursive", "seed": 3, "success": False, "graph_edit_distance": 8.0})
    assert log.getvalue().splitlines() == ["  1/2 scenes, last drawer-only 0: success, GED 0",
                                           "  2/2 scenes, last recursive 3: failed, GED 8"]
