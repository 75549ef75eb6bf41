"""Ctrl-C on the long commands: one line, exit code 130, no traceback, and what finished is kept so a
rerun resumes. A terminal sends SIGINT to the whole process group, workers and worlds included; so
do these tests."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import psutil
import pytest

from agent.app.bench.faults import foreground_sigint

pytestmark = pytest.mark.slow


#: This checkout, ahead of any installed copy on the commands' path (they run in other folders).
ROOT = Path(__file__).resolve().parent.parent


def _start(args: list[str], cwd: Path) -> subprocess.Popen:
    """A `homebot` command of this checkout in a process group of its own, as a shell starts a foreground job."""
    path = os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))
    return subprocess.Popen([sys.executable, "-m", "agent.app.cli", *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True, preexec_fn=foreground_sigint,
                            env={**os.environ, "PYTHONPATH": path})


def _lines(path: Path) -> int:
    return len(path.read_text().splitlines()) if path.exists() else 0


def _interrupt_once(process: subprocess.Popen, path: Path, at_least: int, timeout_s: float = 240.0
                    ) -> tuple[int, str]:
    """Ctrl-C to ``process``'s group once ``path`` holds ``at_least`` lines; its exit code and stderr.
    It must end well within `ENDS_WITHIN_S` of the signal."""
    deadline = time.monotonic() + timeout_s
    while _lines(path) < at_least:
        assert process.poll() is None, process.communicate()[1][-2000:]
        assert time.monotonic() < deadline, f"{path} never reached {at_least} lines"
        time.sleep(0.2)
    return _ctrl_c(process)


#: A bound that proves a command ends on Ctrl-C rather than finishing its work or hanging.
ENDS_WITHIN_S = 10.0


def _ctrl_c(process: subprocess.Popen) -> tuple[int, str]:
    """Ctrl-C to ``process``'s group; its exit code and stderr once it has ended, within `ENDS_WITHIN_S`."""
    os.killpg(process.pid, signal.SIGINT)
    try:
        _, stderr = process.communicate(timeout=ENDS_WITHIN_S)
    except subprocess.TimeoutExpired:
        os.killpg(process.pid, signal.SIGKILL)
        raise AssertionError(f"still running {ENDS_WITHIN_S:g} s after Ctrl-C") from None
    return process.returncode, stderr


def _quiet(code: int, stderr: str) -> None:
    """The command ended as Ctrl-C ends one: exit code 130, one line, no traceback."""
    assert code == 130 and "Traceback" not in stderr and "interrupted" in stderr, stderr


def _whole_lines(path: Path) -> list[dict]:
    """The results a file holds; each line whole JSON (what finished is kept intact)."""
    return [json.loads(line) for line in path.read_text().splitlines()]


@pytest.fixture(scope="module")
def small_suite(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Three scenarios with no hidden evidence, whose episodes are short."""
    from worlds.suite import plan_split, write_suite

    folder = tmp_path_factory.mktemp("suite")
    return write_suite(folder, plan_split(3, [3], 72000, ("suite",)), hidden=False)["suite"]


def _free() -> str:
    from worlds.bus.session import free_tcp_endpoint

    return free_tcp_endpoint()


def test_run_stops_on_ctrl_c_mid_episode_keeping_its_record(tmp_path: Path) -> None:
    process = _start(["run", "--seed", "0", "--out", str(tmp_path / "runs"), "--listen", _free()], tmp_path)
    deadline = time.monotonic() + 240
    while not (logs := list(tmp_path.glob("runs/*/snapshots.jsonl"))) or _lines(logs[0]) < 3:
        assert process.poll() is None, process.communicate()[1][-2000:]
        assert time.monotonic() < deadline, "the episode never got under way"
        time.sleep(0.1)
    _quiet(*_ctrl_c(process))
    result = json.loads(next(tmp_path.glob("runs/*/result.json")).read_text())
    assert result["status"] == "interrupted" and _lines(logs[0]) >= 3


def test_an_evaluation_stops_on_ctrl_c_while_its_workers_start(tmp_path: Path, small_suite: Path) -> None:
    """Ctrl-C while the workers still import: they leave it to the command, which ends quietly."""
    process = _start(["eval", "explore", "--suite", str(small_suite), "--workers", "2", "--methods", "fbe",
                      "--out", str(tmp_path / "out"), "--listen", _free()], tmp_path)
    deadline = time.monotonic() + 120
    while not any(_importing(child) for child in psutil.Process(process.pid).children()):
        assert process.poll() is None, process.communicate()[1][-2000:]
        assert time.monotonic() < deadline, "the workers never started"
        time.sleep(0.01)
    _quiet(*_ctrl_c(process))


def _importing(process: "psutil.Process") -> bool:
    """Whether ``process`` is a pool worker that has begun to load the evaluation's modules (numpy
    is among the first): a Ctrl-C then lands in the middle of its imports."""
    try:
        return "spawn_main" in " ".join(process.cmdline()) and any(
            "numpy" in region.path for region in process.memory_maps())
    except (psutil.NoSuchProcess, psutil.AccessDenied):
        return False


@pytest.mark.parametrize("evaluation", ["explore", "stop"])
def test_an_evaluation_stops_on_ctrl_c_and_a_rerun_resumes(tmp_path: Path, small_suite: Path, evaluation: str) -> None:
    out = tmp_path / "out"
    args = ["eval", evaluation, "--suite", str(small_suite), "--workers", "2", "--out", str(out),
            "--listen", _free(), "--set", "episode.budget=4"]
    if evaluation == "explore":
        args += ["--methods", "fbe,semantic"]
    else:
        args += ["--calibration", str(ROOT / "agent/data/calibration-semantic-sim.json")]
    results = out / ("explore-results.jsonl" if evaluation == "explore" else "stop-episodes.jsonl")
    _quiet(*_interrupt_once(_start(args, tmp_path), results, 1))
    kept = _whole_lines(results)
    total = 6 if evaluation == "explore" else 3
    assert 1 <= len(kept) < total
    rerun = _start(args, tmp_path)
    assert rerun.wait(timeout=600) == 0, rerun.communicate()[1][-2000:]
    again = _whole_lines(results)
    assert again[:len(kept)] == kept and len(again) == total


def test_a_ray_evaluation_stops_on_ctrl_c_keeping_whole_lines_and_leaving_nothing_running(
        tmp_path: Path, small_suite: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """With --ray the command started a local Ray cluster: Ctrl-C cancels its tasks (their worlds end
    with their workers) and shuts it down; every process of the command's group is gone."""
    out = tmp_path / "out"
    with tempfile.TemporaryDirectory(prefix="ray-") as session:  # short: the cluster's socket paths must fit
        monkeypatch.setenv("RAY_TMPDIR", session)
        process = _start(["eval", "explore", "--suite", str(small_suite), "--ray", "--workers", "2", "--methods",
                          "fbe", "--out", str(out), "--set", "episode.budget=4"], tmp_path)
        _quiet(*_interrupt_once(process, out / "explore-results.jsonl", 1))
        assert 1 <= len(_whole_lines(out / "explore-results.jsonl")) < 3
        time.sleep(2.0)  # the cancelled tasks' worlds notice their workers' end within a second
        left = [p for p in psutil.process_iter(["pid"]) if _in_group(p, process.pid)]
    assert left == [], [p.cmdline() for p in left]


@pytest.mark.parametrize("command, results", [
    (["eval", "interactive", "--variants", "2", "--executor", "robot"], "interactive-results.jsonl"),
    (["eval", "coverage", "--homes", "1", "--steps", "80"], "coverage-results.jsonl"),
])
def test_a_scene_evaluation_stops_on_ctrl_c_keeping_whole_lines(tmp_path: Path, command: list[str],
                                                                results: str) -> None:
    out = tmp_path / "out"
    _quiet(*_interrupt_once(_start([*command, "--workers", "2", "--out", str(out)], tmp_path), out / results, 1))
    assert len(_whole_lines(out / results)) >= 1


def test_lfe_data_and_train_stop_on_ctrl_c_keeping_what_finished(tmp_path: Path) -> None:
    data = tmp_path / "data"
    process = _start(["lfe", "data", "--homes", "8", "--workers", "2", "--out", str(data)], tmp_path)
    deadline = time.monotonic() + 240
    while len(list(data.glob("*.npz"))) < 3:
        assert process.poll() is None, process.communicate()[1][-2000:]
        assert time.monotonic() < deadline, "no shard was written"
        time.sleep(0.2)
    _quiet(*_ctrl_c(process))
    shards = sorted(data.glob("*.npz"))
    assert 3 <= len(shards) < 8
    for shard in shards:  # each whole
        with np.load(shard) as arrays:
            assert arrays.files
    train = tmp_path / "train"
    args = ["lfe", "train", "--data", str(data), "--out", str(train), "--epochs", "50", "--steps-per-epoch", "4",
            "--batch-size", "2", "--crop", "64", "--device", "cpu"]
    _quiet(*_interrupt_once(_start(args, tmp_path), train / "history.jsonl", 1))
    assert len(_whole_lines(train / "history.jsonl")) >= 1 and (train / "model.pt").exists()


def test_suite_make_stops_on_ctrl_c_and_a_rerun_resumes(tmp_path: Path) -> None:
    out = tmp_path / "suite"
    args = ["suite", "make", "--n", "400", "--seed-base", "70000", "--out", str(out)]
    code, stderr = _interrupt_once(_start(args, tmp_path), out / "suite.jsonl", 3)
    assert code == 130 and "Traceback" not in stderr and "interrupted" in stderr, stderr
    kept = [json.loads(line) for line in (out / "suite.jsonl").read_text().splitlines()]
    assert 3 <= len(kept) < 400
    rerun = _start([*args[:2], "--n", str(len(kept) + 2), *args[4:]], tmp_path)
    assert rerun.wait(timeout=240) == 0, rerun.communicate()[1]
    again = [json.loads(line) for line in (out / "suite.jsonl").read_text().splitlines()]
    assert again[:len(kept)] == kept and [e["seed"] for e in again] == list(range(70000, 70000 + len(kept) + 2))


def test_calibrate_stops_on_ctrl_c_keeping_finished_episodes_and_leaving_no_world(tmp_path: Path) -> None:
    suite = tmp_path / "suite"
    made = subprocess.run([sys.executable, "-m", "agent.app.cli", "suite", "make", "--n", "6", "--seed-base", "71000",
                           "--hidden", "never", "--out", str(suite)], capture_output=True,
                          text=True, timeout=240)
    assert made.returncode == 0, made.stderr
    out = tmp_path / "calibration.json"
    process = _start(["calibrate", "--suite", str(suite / "suite.jsonl"), "--workers", "1", "--out", str(out),
                      "--set", "episode.budget=6"], tmp_path)
    group = process.pid
    results = next(iter(tmp_path.glob("**/*episodes*.jsonl")), None)
    deadline = time.monotonic() + 240
    while results is None or _lines(results) < 1:
        assert process.poll() is None, process.communicate()[1][-2000:]
        assert time.monotonic() < deadline
        time.sleep(0.2)
        results = next(iter(tmp_path.glob("**/*episodes*.jsonl")), None)
    code, stderr = _interrupt_once(process, results, 1)
    assert code == 130 and "Traceback" not in stderr and "interrupted" in stderr, stderr
    assert 1 <= _lines(results) < 6
    time.sleep(2.0)  # the workers' worlds were told to stop; give them the moment they take
    left = [p for p in psutil.process_iter(["pid"]) if _in_group(p, group)]
    assert left == [], [p.cmdline() for p in left]


def _in_group(process: "psutil.Process", group: int) -> bool:
    try:
        return os.getpgid(process.pid) == group and process.status() != "zombie"
    except (ProcessLookupError, PermissionError, OSError):
        return False
