"""Whole episodes: a spawned world, the agent's tree, snapshots to a watcher, failures recorded."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from worlds.bus.keys import ANY_AGENT_TREE
from worlds.bus.session import free_tcp_endpoint, open_session
from agent.app.config import load_config
from agent.app.runtime.run import RunRequest, run_episode
from agent.app.tree_state import behaviour_rows, fold, read_log

pytestmark = pytest.mark.slow


def _config(agent_endpoint: str, budget: int):
    return load_config(overrides=[f'bus.listen=["{agent_endpoint}"]', f"episode.budget={budget}", "stop.rule=budget"])


def test_episode_answers_while_a_separate_subscriber_receives_snapshots(tmp_path: Path) -> None:
    agent_endpoint = free_tcp_endpoint()
    watcher = open_session(connect=[agent_endpoint])
    received: list[dict] = []
    subscriber = watcher.declare_subscriber(ANY_AGENT_TREE, lambda s: received.append(json.loads(s.payload.to_bytes())))
    try:
        result = run_episode(RunRequest(seed=3, config=_config(agent_endpoint, budget=5), out_root=tmp_path))
    finally:
        subscriber.undeclare()
        watcher.close()

    assert result["status"] == "answered", result["reason"]
    assert result["answer"] in "ABCD" and result["ground_truth"] in "ABCD"
    assert result["correct"] == (result["answer"] == result["ground_truth"])
    assert result["steps"] == 5
    folder = Path(result["folder"])
    on_disk = json.loads((folder / "result.json").read_text())
    assert on_disk["question"] == result["question"] and on_disk["answer"] == result["answer"]
    logged = [json.loads(line) for line in (folder / "snapshots.jsonl").read_text().splitlines()]
    assert logged and logged[-1]["tick"] == result["ticks"]
    assert (folder / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert received, "the separate subscriber got no snapshot"
    assert {s["run"] for s in received} == {result["run_id"]}
    names = {b["name"] for b in received[0]["tree"]}
    assert {"Observe", "IntegrateMap", "QueryVLM", "SelectFrontier", "Navigate", "AnswerFallback"} <= names


def test_same_seed_gives_the_same_episode(tmp_path: Path) -> None:
    results = [
        run_episode(RunRequest(seed=5, config=_config(free_tcp_endpoint(), budget=4), out_root=tmp_path / str(i)))
        for i in range(2)
    ]
    for key in ("question", "choices", "answer", "ground_truth", "steps"):
        assert results[0][key] == results[1][key], key
    moves = [_navigate_messages(Path(result["folder"]) / "snapshots.jsonl") for result in results]
    assert moves[0] and moves[0] == moves[1]


def _navigate_messages(log: Path) -> list[str]:
    """Where each step's move ended, in order, read from the snapshot log."""
    messages: list[str] = []
    for state in fold(read_log(log.read_text())):
        for behaviour in behaviour_rows(state):
            if behaviour["name"] == "Navigate" and behaviour["status"] == "SUCCESS" and behaviour["visited"]:
                if not messages or messages[-1] != behaviour["message"]:
                    messages.append(behaviour["message"])
    return messages


def _start_world(namespace: str, endpoint: str) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "worlds.server", "--namespace", namespace, "--listen", endpoint],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
    )


def test_killed_world_fails_the_episode_with_the_reason_within_five_seconds(tmp_path: Path) -> None:
    namespace, world_endpoint = "homebot/killtest", free_tcp_endpoint()
    world = _start_world(namespace, world_endpoint)
    outcome: dict = {}

    def run() -> None:
        request = RunRequest(seed=2, config=_config(free_tcp_endpoint(), budget=500), out_root=tmp_path,
                             connect=world_endpoint, namespace=namespace, run_id="killed")
        outcome.update(run_episode(request))

    runner = threading.Thread(target=run, daemon=True)
    try:
        runner.start()
        snapshots = tmp_path / "killed" / "snapshots.jsonl"
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline and not (snapshots.exists() and '"step 2:' in snapshots.read_text()):
            time.sleep(0.05)
        assert runner.is_alive(), "the episode ended before the world could be killed"
        os.kill(world.pid, signal.SIGKILL)
        killed_at = time.monotonic()
        runner.join(timeout=30)
        ended_after = time.monotonic() - killed_at
    finally:
        world.kill()
        world.wait()
    assert not runner.is_alive(), "the agent hung after the world died"
    assert ended_after < 5.0, f"the agent took {ended_after:.1f} s to notice"
    assert outcome["status"] == "failed"
    assert "world" in outcome["reason"] and outcome["failed_behaviour"] in {"Observe", "Navigate"}
    recorded = json.loads((tmp_path / "killed" / "result.json").read_text())
    assert recorded["status"] == "failed" and recorded["reason"] == outcome["reason"]


def test_run_and_watch_from_the_command_line(tmp_path: Path) -> None:
    agent_endpoint = free_tcp_endpoint()
    run = subprocess.Popen(
        [sys.executable, "-m", "agent.app.cli", "run", "--seed", "1", "--listen", agent_endpoint,
         "--set", "episode.budget=8", "--set", "episode.tick_period_s=0.2",  # paced: still running when watched
         "--out", str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    try:
        watch = subprocess.run(
            [sys.executable, "-m", "agent.app.cli", "watch", "--connect", agent_endpoint, "--once", "--json",
             "--timeout", "60"],
            capture_output=True, text=True, timeout=120,
        )
        stdout, stderr = run.communicate(timeout=300)
    finally:
        run.kill()
    assert watch.returncode == 0, watch.stderr
    snapshot = json.loads(watch.stdout)
    assert snapshot["tree"][0]["name"] == "EQA episode" and snapshot["behaviours"]
    assert run.returncode == 0, stderr
    assert "answer " in stdout and "run folder:" in stdout


def test_a_bad_setting_is_rejected_with_its_name() -> None:
    done = subprocess.run([sys.executable, "-m", "agent.app.cli", "run", "--set", "map.resolution=fine"],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert "map.resolution" in done.stderr


def test_a_semantic_episode_shows_the_vlm_its_visual_prompts(tmp_path: Path) -> None:
    config = load_config(overrides=[f'bus.listen=["{free_tcp_endpoint()}"]', "episode.budget=6",
                                    "explore.method=semantic"])
    result = run_episode(RunRequest(seed=4, config=config, out_root=tmp_path))
    assert result["status"] == "answered", result["reason"]
    images = sorted((Path(result["folder"]) / "prompts").glob("step-*.png"))
    assert images and images[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    log = Path(result["folder"]) / "snapshots.jsonl"
    messages = {b["message"] for state in fold(read_log(log.read_text())) for b in behaviour_rows(state)
                if b["name"] == "QueryDirections" and b["status"] == "SUCCESS"}
    assert any("LSV favours" in m for m in messages)


def test_eval_explore_runs_in_workers_and_resumes(tmp_path: Path) -> None:
    from agent.app.eval.method_comparison import evaluate_explore
    from worlds.suite import plan_split, write_suite

    suite = write_suite(tmp_path / "suite", plan_split(2, [2], 50, ("suite",)))["suite"]
    config = load_config(overrides=["bus.listen=[]", "episode.budget=4"])
    out = tmp_path / "eval"
    report = evaluate_explore(suite, ["fbe", "semantic"], out, workers=2, config=config)
    lines = (out / "explore-results.jsonl").read_text().splitlines()
    assert len(lines) == 4 and report["failed"] == 0
    assert [json.loads(line)["steps"] for line in lines] == [4] * 4  # every method runs to its budget
    assert set(report["curves"]) == {"fbe", "semantic"} and report["counts"] == {"fbe": 2, "semantic": 2}
    assert (out / "curves.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    header = (out / "curves.csv").read_text().splitlines()[0]
    assert header == ("normalised_time,fbe (n=2),semantic (n=2),fbe target seen (n=2),semantic target seen (n=2),"
                      "fbe floor seen (n=2),semantic floor seen (n=2),fbe rooms entered (n=2),semantic rooms entered (n=2)")
    assert set(report["target_seen"]) == {"fbe", "semantic"} and report["target_seen_counts"] == report["counts"]
    assert all(0 < curve[-1] <= 1 for curve in report["floor_seen"].values())
    assert all(curve[-1] >= 1 for curve in report["rooms_entered"].values())
    evaluations = [json.loads(line)["evaluation"] for line in lines]
    assert all(e["head_frames"] == 4 and e["rooms_entered"] and "rooms" not in e for e in evaluations)
    assert all(len(e["floor_seen_by_frame"]) == 4 and e["floor_seen_by_frame"] == sorted(e["floor_seen_by_frame"])
               for e in evaluations)
    evaluate_explore(suite, ["fbe", "semantic"], out, workers=2, config=config)  # nothing left to do
    assert (out / "explore-results.jsonl").read_text().splitlines() == lines
