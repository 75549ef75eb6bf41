"""Ctrl-C on the long commands: one line, exit code 130, no traceback, and what finished is kept so a
rerun resumes. A terminal sends SIGINT to the whole process group, workers and worlds included; so
do these tests."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow


def _start(args: list[str], cwd: Path) -> subprocess.Popen:
    """A `homebot` command in a process group of its own, as a shell starts a foreground job."""
    return subprocess.Popen([sys.executable, "-m", "agent.app.cli", *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def _lines(path: Path) -> int:
    return len(path.read_text().splitlines()) if path.exists() else 0


def _interrupt_once(process: subprocess.Popen, path: Path, at_least: int, timeout_s: float = 240.0
                    ) -> tuple[int, str]:
    """Ctrl-C to ``process``'s group once ``path`` holds ``at_least`` lines; its exit code and stderr."""
    deadline = time.monotonic() + timeout_s
    while _lines(path) < at_least:
        assert process.poll() is None, process.communicate()[1][-2000:]
        assert time.monotonic() < deadline, f"{path} never reached {at_least} lines"
        time.sleep(0.2)
    os.killpg(process.pid, signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    return process.returncode, stderr


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
    import psutil

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
