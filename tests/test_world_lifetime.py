"""A world the agent starts is the agent's to end: it ends within seconds of the process that
started it, even one killed without cleanup, and ignores the Ctrl-C a terminal sends the whole
process group, which the agent answers by ending its episode as interrupted and then the world."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from agent.app.config import CameraSettings
from agent.app.runtime.world_process import WorldProcess
from worlds.bus.session import free_tcp_endpoint

#: How long a world may take to notice that its parent ended (it looks twice a second) or to stop.
WORLD_ENDS_WITHIN_S = 10.0


def test_a_world_ends_when_the_process_that_started_it_is_killed(tmp_path: Path) -> None:
    starter = subprocess.Popen(
        [sys.executable, "-c",
         "import sys, time; from pathlib import Path; from agent.app.config import CameraSettings; "
         "from agent.app.runtime.world_process import WorldProcess; "
         "from worlds.bus.session import free_tcp_endpoint; "
         "w = WorldProcess('homebot/eval-orphan', free_tcp_endpoint(), CameraSettings(), "
         f"Path({str(tmp_path)!r}) / 'w.log'); "
         "print(w.process.pid, flush=True); time.sleep(120)"],
        stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parents[1])})
    world = psutil.Process(int(starter.stdout.readline()))
    starter.kill()  # SIGKILL: no cleanup of its own runs
    starter.wait()
    try:
        world.wait(WORLD_ENDS_WITHIN_S)
    except psutil.TimeoutExpired:
        world.kill()
        raise AssertionError("the world outlived the process that started it") from None
    assert "has ended; stopping" in (tmp_path / "w.log").read_text()


def test_a_world_with_a_parent_leaves_ctrl_c_to_it_and_ends_on_sigterm(tmp_path: Path) -> None:
    world = WorldProcess("homebot/lifetime", free_tcp_endpoint(), CameraSettings(), tmp_path / "w.log")
    try:
        deadline = time.monotonic() + 60
        while "serving" not in (tmp_path / "w.log").read_text():
            assert world.process.poll() is None and time.monotonic() < deadline, (tmp_path / "w.log").read_text()
            time.sleep(0.1)
        world.process.send_signal(signal.SIGINT)
        with pytest.raises(subprocess.TimeoutExpired):
            world.process.wait(2.0)
        world.process.send_signal(signal.SIGTERM)
        assert world.process.wait(WORLD_ENDS_WITHIN_S) == 0
    finally:
        world.stop()
