"""Evaluations on a Ray cluster (``--ray``): the same records as the process pool, a run stopped
part-way resumes without redoing what finished, a task whose worker is killed mid-episode is run
again and recorded once, tasks join running worlds one at a time, and no world is left behind.
The tests share one local cluster of two CPUs, its files in a temporary folder."""

from __future__ import annotations

import json
import logging
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import psutil
import pytest

from agent.app.cli import main
from agent.app.config import Config, load_config
from agent.app.eval.calibrate import full_budget_jobs
from agent.app.eval.interactive import evaluate_interactive
from agent.app.eval.lfe_data import generate_dataset
from agent.app.eval.runner import Job, WorldAddress, comparable, read_results, run_jobs
from agent.app.runtime.ray_backend import LOCAL, NEEDS_RAY
from agent.lfe.samples import DataConfig
from agent.lfe.shards import load_shard, shard_path
from agent.lfe.task import CoverageConfig
from worlds.bus.session import free_tcp_endpoint
from worlds.suite import plan_split, write_suite

#: How long a killed process's world may take to notice and end (it looks twice a second).
WORLD_ENDS_WITHIN_S = 10.0


@pytest.fixture(scope="module")
def ray_cluster() -> Iterator[None]:
    """A local Ray cluster of two CPUs for this module, its session files in a temporary folder
    (a short one: its socket paths must fit); shut down (every process of it ended) afterwards."""
    import ray

    with tempfile.TemporaryDirectory(prefix="ray-") as session:
        ray.init(address=LOCAL, num_cpus=2, include_dashboard=False, log_to_driver=False,
                 logging_level=logging.ERROR, _temp_dir=session)
        yield
        ray.shutdown()


def _config(budget: int) -> Config:
    return load_config(overrides=["bus.listen=[]", f"episode.budget={budget}"])


def _jobs(folder: Path, entries: int, seed_base: int, config: Config) -> list[Job]:
    suite = write_suite(folder / "suite", plan_split(entries, [entries], seed_base, ("ray",)), hidden=False)["ray"]
    return full_budget_jobs(suite, config)


def _own_worlds() -> list[psutil.Process]:
    """The world processes that evaluation episodes started and that still run."""
    found = []
    for process in psutil.process_iter(["cmdline", "status"]):
        command = " ".join(process.info["cmdline"] or [])
        if "worlds.server" in command and "homebot/eval-" in command and process.info["status"] != "zombie":
            found.append(process)
    return found


def _worlds_end() -> list[psutil.Process]:
    """The evaluation worlds still running once they have had `WORLD_ENDS_WITHIN_S` to end."""
    deadline = time.monotonic() + WORLD_ENDS_WITHIN_S
    while (left := _own_worlds()) and time.monotonic() < deadline:
        time.sleep(0.2)
    return left


@pytest.mark.slow
def test_ray_tasks_give_the_records_the_process_pool_gives(ray_cluster: None, tmp_path: Path) -> None:
    config = _config(3)
    jobs = _jobs(tmp_path, 2, 75000, config)
    assert run_jobs(jobs, tmp_path / "pool.jsonl", 1, config) == 2
    assert run_jobs(jobs, tmp_path / "ray.jsonl", 1, config, ray=LOCAL) == 2
    pool, on_ray = read_results(tmp_path / "pool.jsonl"), read_results(tmp_path / "ray.jsonl")
    assert [r["status"] for r in on_ray] != ["failed"] * 2 and all(r["steps"] == 3 for r in on_ray), on_ray
    assert comparable(on_ray) == comparable(pool)
    assert _worlds_end() == []


@pytest.mark.slow
def test_a_ray_run_stopped_part_way_keeps_what_finished_and_a_rerun_does_the_rest(ray_cluster: None,
                                                                                   tmp_path: Path) -> None:
    config = load_config(overrides=["bus.listen=[]", "episode.budget=3", "ray.cpus_per_episode=1"])  # two at once
    jobs = _jobs(tmp_path, 3, 75100, config)
    results = tmp_path / "results.jsonl"

    def ctrl_c(done: int, total: int, result: dict) -> None:
        raise KeyboardInterrupt  # as Ctrl-C does once the first episode is in, the others under way

    with pytest.raises(KeyboardInterrupt):
        run_jobs(jobs, results, 2, config, ctrl_c, ray=LOCAL)
    kept = results.read_text().splitlines()
    assert len(kept) == 1
    assert _worlds_end() == [], "the cancelled tasks left their worlds running"
    assert run_jobs(jobs, results, 2, config, ray=LOCAL) == 2
    lines = results.read_text().splitlines()
    assert lines[:1] == kept
    assert sorted(json.loads(line)["id"] for line in lines) == sorted(job.entry_id for job in jobs)


@pytest.mark.slow
def test_a_task_whose_worker_is_killed_mid_episode_is_run_again_and_recorded_once(ray_cluster: None,
                                                                                  tmp_path: Path) -> None:
    config = _config(12)
    jobs = _jobs(tmp_path, 1, 75200, config)
    killed: list[int] = []
    done = threading.Event()

    def kill_the_worker_mid_episode() -> None:
        """SIGKILL the Ray worker running the episode once its tree has ticked, as a node's
        out-of-memory killer would: no cleanup of the worker's runs."""
        while not done.is_set():
            for world in _own_worlds():
                run_folder = Path(os.readlink(f"/proc/{world.pid}/fd/1")).parent  # the world logs into it
                snapshots = run_folder / "snapshots.jsonl"
                if snapshots.exists() and len(snapshots.read_text().splitlines()) >= 2:
                    killed.append(world.pid)
                    psutil.Process(world.ppid()).send_signal(signal.SIGKILL)
                    return
            time.sleep(0.05)

    killer = threading.Thread(target=kill_the_worker_mid_episode, daemon=True)
    killer.start()
    try:
        assert run_jobs(jobs, tmp_path / "results.jsonl", 1, config, ray=LOCAL) == 1
    finally:
        done.set()
        killer.join(10)
    assert killed, "no worker was killed: the episode ended before it was seen under way"
    results = read_results(tmp_path / "results.jsonl")
    assert len(results) == 1
    assert results[0]["status"] != "failed" and results[0]["steps"] == 12, results[0]
    assert _worlds_end() == [], "the killed worker's world was left running"


@pytest.mark.slow
def test_homes_explored_as_ray_tasks_give_the_same_shards(ray_cluster: None, tmp_path: Path) -> None:
    config = DataConfig(coverage=CoverageConfig(budget_steps=10), record_every=1)
    seeds = [27, 30]
    generate_dataset(tmp_path / "here", seeds, config, workers=1)
    summary = generate_dataset(tmp_path / "ray", seeds, config, ray=LOCAL)
    assert sorted(summary.written) == seeds
    for seed in seeds:
        here, there = load_shard(shard_path(tmp_path / "here", seed)), load_shard(shard_path(tmp_path / "ray", seed))
        for name in here:
            np.testing.assert_array_equal(here[name], there[name])


#: What a robot scene's row holds that is the machine's speed, not the exploration's.
SCENE_TIMING = ("seconds", "skill_seconds", "planning_ms", "skill_times")


@pytest.mark.slow
def test_a_robot_scene_explored_as_a_ray_task_gives_the_row_a_worker_process_gives(ray_cluster: None,
                                                                                     tmp_path: Path) -> None:
    here = evaluate_interactive(tmp_path / "pool", ["door-only"], 1, "robot")
    there = evaluate_interactive(tmp_path / "ray", ["door-only"], 1, "robot", ray=LOCAL)
    assert there["n"] == 1 and there["table"] == here["table"]
    rows = [{key: value for key, value in read_results(Path(report["results"]))[0].items() if key not in SCENE_TIMING}
            for report in (here, there)]
    assert rows[0]["success"] and rows[0]["actions"] > 0, rows[0]
    assert rows[1] == rows[0]


@pytest.mark.slow
def test_ray_tasks_take_turns_in_a_running_world_they_join(ray_cluster: None, tmp_path: Path) -> None:
    config = _config(2)
    jobs = _jobs(tmp_path, 2, 75300, config)
    endpoint = free_tcp_endpoint()
    world = subprocess.Popen([sys.executable, "-m", "agent.app.cli", "world", "--namespace", "homebot/far",
                              "--listen", endpoint], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        assert run_jobs(jobs, tmp_path / "results.jsonl", 1, config, worlds=[WorldAddress(endpoint, "homebot/far")],
                        ray=LOCAL) == 2
    finally:
        world.terminate()
        world.wait(10)
    results = read_results(tmp_path / "results.jsonl")
    assert [r["status"] != "failed" and r["steps"] == 2 for r in results] == [True, True], results


@pytest.mark.parametrize("command", [["calibrate", "--suite", "s.jsonl"], ["eval", "coverage"],
                                     ["eval", "interactive"], ["lfe", "data", "--homes", "1"]])
def test_ray_without_the_package_says_how_to_install_it(command: list[str], monkeypatch: pytest.MonkeyPatch,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` fails as it does where it is not installed
    assert _exit_code([*command, "--ray"]) == 2
    assert NEEDS_RAY in capsys.readouterr().err


def _exit_code(argv: list[str]) -> int:
    """What `homebot` ARGV exits with, whether its parser exits or its command returns."""
    try:
        return main(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)
