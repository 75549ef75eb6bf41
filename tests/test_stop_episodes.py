"""Stopping rules in whole episodes: the tree stops where a replay of the scores says, calibrations
are refused when they do not fit, and an interrupted calibration resumes."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from worlds.bus.session import free_tcp_endpoint
from agent.app.config import Config, load_config
from agent.eqa.answers import StepScores, steps_from_records
from agent.eqa.calibration import Calibration, CalibrationEpisode, read_calibration
from agent.app.runtime.calibrations import made_with, shipped_calibration, write_calibration
from agent.app.tree_state import behaviour_rows, fold
from agent.eqa.stopping import ConformalRule, RelevanceRule, replay
from agent.app.runtime.run import RunError, RunRequest, run_episode
from worlds.suite import plan_split, write_suite
from worlds.bus.questions import LETTERS


def _config(*overrides: str) -> Config:
    return load_config(overrides=[f'bus.listen=["{free_tcp_endpoint()}"]', *overrides])


def _steps(result: dict) -> list[StepScores]:
    return steps_from_records(result["step_scores"])


def _calibration_with_q_hat(config: Config, q_hat: float, n: int = 9) -> Calibration:
    """A calibration whose every κ is ``q_hat`` (so q̂(ε) is ``q_hat`` for any ε ≥ 1/(n+1)).

    One step with Rel = q̂ − 1 and f̂_truth = 0 gives κ = 1 − (q̂ − 1)·(0 − 1) = q̂.
    """
    step = {"step": 1, "answer_probs": {"A": 0.0, "B": 1.0, "C": 0.0, "D": 0.0}, "relevance": q_hat - 1.0}
    episodes = [CalibrationEpisode(f"c{i}", i, "A", [step]) for i in range(n)]
    return Calibration(made_with(config), {"file": "hand-made", "sha256": "", "entries": n}, episodes, [])


def test_a_calibration_of_another_policy_is_refused_before_the_world_starts(tmp_path: Path) -> None:
    config = _config("explore.method=semantic-no-lsv", f"stop.calibration={shipped_calibration(Config())}")
    with pytest.raises(RunError) as raised:
        run_episode(RunRequest(seed=1, config=config, out_root=tmp_path, run_id="refused"))
    text = str(raised.value)
    assert "explore.method" in text and "'semantic'" in text and "'semantic-no-lsv'" in text
    assert "stop.accept_mismatched_calibration" in text
    record = json.loads((tmp_path / "refused" / "result.json").read_text())
    assert record["status"] == "failed" and "calibration" in record["reason"]
    assert not (tmp_path / "refused" / "world.log").exists(), "a world was started for a run that cannot run"


def test_a_method_with_no_shipped_calibration_is_refused_with_what_to_do(tmp_path: Path) -> None:
    with pytest.raises(RunError, match="no calibration ships for explore.method=semantic-no-gsv"):
        run_episode(RunRequest(seed=1, config=_config("explore.method=semantic-no-gsv"), out_root=tmp_path))


def test_the_shipped_calibration_fits_the_default_policy() -> None:
    calibration = read_calibration(shipped_calibration(Config()))
    assert made_with(Config()) == calibration.made_with
    assert len(calibration.episodes) >= 100
    assert 1.0 <= calibration.q_hat(0.3) <= 2.0


@pytest.mark.slow
def test_the_tree_stops_where_a_replay_of_the_full_episode_says(tmp_path: Path) -> None:
    seed, budget = 3, 8
    full = run_episode(RunRequest(seed=seed, config=_config(f"episode.budget={budget}", "stop.rule=budget"),
                                  out_root=tmp_path / "full", save_map=False))
    assert full["steps"] == budget and full["stop"] == {"rule": "budget", "threshold": None}
    steps = _steps(full)

    # a q̂ under which the conformal set narrows to one answer after a few steps, not at once
    stops = {}
    for q_hat in np.round(np.linspace(1.0, 2.0, 201), 3):
        decision = replay(ConformalRule(float(q_hat), 0.3, LETTERS), steps, budget)
        if 2 <= decision.step < budget and "set is" in decision.reason:
            stops[float(q_hat)] = decision
    assert stops, "no q̂ narrows this episode's set to one answer; pick another seed"
    q_hat, expected = sorted(stops.items())[len(stops) // 2]
    calibration_file = tmp_path / "calibration.json"
    config = _config(f"episode.budget={budget}", "stop.rule=cp", f"stop.calibration={calibration_file}")
    write_calibration(calibration_file, _calibration_with_q_hat(config, q_hat))

    early = run_episode(RunRequest(seed=seed, config=config, out_root=tmp_path / "cp", save_map=False))
    assert early["status"] == "answered", early["reason"]
    assert early["steps"] == expected.step < budget
    assert early["answer"] == expected.letter and early["prediction_set"] == [expected.letter]
    assert early["step_scores"] == full["step_scores"][: expected.step]  # same episode up to the stop
    assert early["stop"]["rule"] == "cp" and early["stop"]["q_hat"] == pytest.approx(q_hat)
    assert early["answer_detail"]["rule"].startswith("conformal set is")
    assert early["acts"] == []  # a question about no storage: nothing opened
    snapshots = [json.loads(line) for line in (Path(early["folder"]) / "snapshots.jsonl").read_text().splitlines()]
    shown = {key.lstrip("/") for snapshot in snapshots for key in snapshot["blackboard"]}
    assert {"prediction_set", "q_hat", "epsilon"} <= shown
    states = fold(snapshots)
    answered = [b for b in behaviour_rows(states[-1]) if b["name"] == "Answer"]
    assert answered and answered[0]["status"] == "SUCCESS"
    navigations = sum(1 for s in states for b in behaviour_rows(s)
                      if b["name"] == "Navigate" and b["status"] == "SUCCESS" and b["visited"])
    assert navigations > 0

    threshold = float(np.median([s.relevance for s in steps[:-1]]))
    expected = replay(RelevanceRule(threshold), steps, budget)
    relevance = run_episode(RunRequest(
        seed=seed, config=_config(f"episode.budget={budget}", "stop.rule=relevance",
                                  f"stop.relevance_threshold={threshold}"),
        out_root=tmp_path / "relevance", save_map=False))
    assert (relevance["steps"], relevance["answer"]) == (expected.step, expected.letter)


@pytest.mark.slow
def test_an_interrupted_calibration_resumes_without_redoing_finished_episodes(tmp_path: Path) -> None:
    suite = write_suite(tmp_path / "suite", plan_split(3, [3], 70, ("calib",)))["calib"]
    out = tmp_path / "cal" / "calibration.json"
    episodes = out.with_name("calibration.episodes.jsonl")
    command = [sys.executable, "-m", "agent.app.cli", "calibrate", "--suite", str(suite), "--workers", "1",
               "--set", "episode.budget=3", "--out", str(out)]
    first = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (episodes.exists() and episodes.read_text().count("\n") >= 1):
        time.sleep(0.1)
    os.killpg(first.pid, signal.SIGKILL)  # the whole group: the CLI, its worker and the worker's world
    first.wait()
    kept = episodes.read_text().splitlines()
    assert 1 <= len(kept) < 3, "the calibration was not interrupted mid-way"
    assert not out.exists()

    subprocess.run(command, check=True, capture_output=True, timeout=240)
    lines = episodes.read_text().splitlines()
    assert lines[: len(kept)] == kept
    ids = [json.loads(line)["id"] for line in lines]
    assert sorted(ids) == ["calib-0000", "calib-0001", "calib-0002"]
    calibration = read_calibration(out)
    assert len(calibration.episodes) == 3 and calibration.suite["entries"] == 3
    assert calibration.made_with == made_with(load_config(overrides=["episode.budget=3"]))


@pytest.mark.slow
def test_eval_stop_writes_the_sweep_and_the_coverage_table_and_resumes(tmp_path: Path) -> None:
    from agent.app.eval.stop import EPSILONS, evaluate_stop

    suite = write_suite(tmp_path / "suite", plan_split(2, [2], 80, ("test",)))["test"]
    config = load_config(overrides=["bus.listen=[]", "episode.budget=3"])
    calibration_file = tmp_path / "calibration.json"
    write_calibration(calibration_file, _calibration_with_q_hat(config, 1.5))
    out = tmp_path / "stop"
    out.mkdir()
    report = evaluate_stop(suite, calibration_file, out, workers=1, config=config)
    assert report["n"] == 2 and report["failed"] == 0
    assert {p.rule for p in report["points"]} == {"budget", "cp", "entropy", "relevance"}
    assert all(0 < p.normalised_steps <= 1 and 0 <= p.success <= 1 for p in report["points"])
    assert [row["epsilon"] for row in report["coverage"]] == list(EPSILONS)
    assert (out / "stop-curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "coverage.csv").read_text().startswith("epsilon,promised,q_hat,coverage")
    episodes = (out / "stop-episodes.jsonl").read_text().splitlines()
    assert [json.loads(line)["steps"] for line in episodes] == [3, 3]  # full budget, whatever the rule
    evaluate_stop(suite, calibration_file, out, workers=1, config=config)
    assert (out / "stop-episodes.jsonl").read_text().splitlines() == episodes

    other = load_config(overrides=["bus.listen=[]", "episode.budget=3", "vlm.sim.skill=0.5"])
    with pytest.raises(Exception, match="vlm.sim.skill"):
        evaluate_stop(suite, calibration_file, tmp_path / "elsewhere", workers=1, config=other)


@pytest.mark.slow
def test_calibration_workers_join_running_worlds_given_by_endpoint(tmp_path: Path) -> None:
    from agent.eqa.calibration import CalibrationError
    from agent.app.eval.calibrate import calibrate
    from agent.app.eval.runner import WorldAddress

    suite = write_suite(tmp_path / "suite", plan_split(2, [2], 90, ("calib",)))["calib"]
    config = load_config(overrides=["bus.listen=[]", "episode.budget=2", "bus.world_start_timeout_s=3"])
    endpoint = free_tcp_endpoint()
    world = subprocess.Popen([sys.executable, "-m", "agent.app.cli", "world", "--namespace", "homebot/far",
                              "--listen", endpoint], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        calibration = calibrate(suite, tmp_path / "joined.json", 2, config,
                                worlds=[WorldAddress(endpoint, "homebot/far")])
    finally:
        world.terminate()
        world.wait(10)
    assert len(calibration.episodes) == 2 and not calibration.failed

    # with no world at the given endpoint the workers do not start worlds of their own: episodes fail
    with pytest.raises(CalibrationError, match="no calibration episode finished"):
        calibrate(suite, tmp_path / "nobody.json", 2, config, worlds=[WorldAddress(free_tcp_endpoint())])
    reasons = {json.loads(line)["reason"] for line in (tmp_path / "nobody.episodes.jsonl").read_text().splitlines()}
    assert all("no world answers" in reason for reason in reasons), reasons
