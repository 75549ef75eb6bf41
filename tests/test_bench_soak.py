"""`homebot bench soak`: what counts as crosstalk, and the report of a short real soak: lanes side by
side against worlds of their own, no failures, no crosstalk, memory per process."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from agent.app.bench.soak import crosstalk_problems
from agent.app.cli import main
from worlds.home import generate_home
from worlds.scenario import make_scenario
from worlds.targets import question_target


def _own_result(seed: int, namespace: str) -> dict[str, Any]:
    """A result as a lane's own world answers it for ``seed``: its scenario, its evaluator's target."""
    home = generate_home(seed)
    scenario = make_scenario(home, seed)
    target = json.loads(json.dumps(question_target(home, scenario.target).to_dict()))
    return {"namespace": namespace, "question": scenario.question, "ground_truth": scenario.answer, "steps": 4,
            "evaluation": {"target": target, "head_frames": 5}}


def test_a_result_from_the_lanes_own_world_has_no_crosstalk() -> None:
    assert crosstalk_problems(_own_result(3, "homebot/soak-1"), "homebot/soak-1", 3) == []


def test_each_sign_of_another_world_is_named() -> None:
    other = _own_result(7, "homebot/soak-1")
    problems = crosstalk_problems(other, "homebot/soak-1", 3)
    assert any(p.startswith("the reset was answered with another home's scenario") for p in problems)
    assert any(p.startswith("the evaluator's record is of another target") for p in problems)
    reset_midway = {**_own_result(3, "homebot/soak-0"), "steps": 9}
    assert crosstalk_problems(reset_midway, "homebot/soak-1", 3) == [
        "the agent ran under 'homebot/soak-0', not 'homebot/soak-1'",
        "the evaluator saw 5 head frames in 9 steps: the world was reset during the episode"]
    named = _own_result(3, "homebot/soak-1")
    named["evaluation"]["namespace"] = "homebot/soak-2"
    assert crosstalk_problems(named, "homebot/soak-1", 3) == ["the evaluator's record came from 'homebot/soak-2'"]


@pytest.mark.parametrize("options, named", [(["--runs", "0"], "--runs must be at least 1"),
                                            (["--minutes", "nan"], "--minutes must be a number above 0"),
                                            (["--episodes", "0"], "--episodes must be at least 1"),
                                            (["--seeds", "0"], "--seeds must be at least 1")])
def test_bad_options_are_refused_before_any_world_starts(tmp_path: Path, options: list[str], named: str,
                                                         capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "soak", *options, "--out", str(tmp_path / "soak.jsonl")]) == 2
    assert named in capsys.readouterr().err
    assert not list(tmp_path.iterdir())


@pytest.mark.slow
def test_a_short_soak_reports_every_lane_no_failures_no_crosstalk_and_memory(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "soak.jsonl"
    code = main(["bench", "soak", "--runs", "2", "--episodes", "2", "--seeds", "1", "--minutes", "5",
                 "--set", "episode.budget=2", "--set", "stop.rule=budget", "--out", str(out), "--json"])
    captured = capsys.readouterr()
    report = json.loads(captured.out)
    assert code == 0, report
    assert report["episodes"] == 4  # two per lane: --episodes ends the soak before --minutes
    assert report["failures"] == [] and report["crosstalk"] == {"checked": 4, "problems": []}
    assert [(lane["lane"], lane["namespace"], lane["episodes"]) for lane in report["lanes"]] == [
        (0, "homebot/soak-0", 2), (1, "homebot/soak-1", 2)]
    assert len({lane["endpoint"] for lane in report["lanes"]}) == 2
    processes = report["memory"]["processes"]
    assert sorted(processes) == ["agent-0", "agent-1", "world-0", "world-1"]
    for row in processes.values():  # one seed a lane: its second episode is compared with its first
        assert row["episodes"] == 2 and row["rounds"] == 2
        assert row["first_mb"] > 0 and row["last_mb"] > 0
        assert row["growth"] == round(row["last_mb"] / row["first_mb"] - 1, 4)
    lines = [json.loads(line) for line in out.read_text().splitlines()]
    kinds = [line["kind"] for line in lines]
    assert kinds.count("episode") == 4 and kinds[-1] == "report"
    assert kinds.count("memory") >= 1  # at the end, and each minute before
    assert sorted((line["lane"], line["seed"]) for line in lines if line["kind"] == "episode") == [
        (0, 0), (0, 0), (1, 1), (1, 1)]  # each lane goes round its own seed
    assert "lane 0 episode 1 (seed 0): answered" in captured.err
    assert (tmp_path / "soak-worlds" / "world-1.log").is_file()
