"""Agents side by side: two `homebot run` on one listen endpoint both finish, a watcher lists and
attaches to each through that endpoint, and Ctrl-C ends an episode as interrupted."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import psutil
import pytest

from worlds.bus.session import free_tcp_endpoint, open_session
from agent.app.agents import AgentInfo, find_agents, open_agent_session
from agent.app.bench.faults import foreground_sigint

pytestmark = pytest.mark.slow


def test_an_agent_key_names_run_namespace_and_endpoint_and_reads_back() -> None:
    agent = AgentInfo("20250101-120000-seed0-ab12", "homebot/20250101-120000-seed0-ab12", "tcp/127.0.0.1:7450")
    assert agent.key == ("homebot/agents/20250101-120000-seed0-ab12/homebot.20250101-120000-seed0-ab12/"
                         "tcp/127.0.0.1:7450")
    assert AgentInfo.from_key(agent.key) == agent
    with pytest.raises(ValueError, match="endpoint 'unixsock-stream//tmp/x'"):
        AgentInfo("r", "homebot/r", "unixsock-stream//tmp/x").key
    with pytest.raises(ValueError, match="agent key 'homebot/agents/r'"):
        AgentInfo.from_key("homebot/agents/r")


def test_a_taken_endpoint_moves_the_agent_and_the_taken_one_still_reaches_it() -> None:
    default = free_tcp_endpoint()
    first, first_listen = open_agent_session([default], [])
    second, second_listen = open_agent_session([default], [])
    watcher = open_session(connect=[default])
    try:
        assert first_listen == [default] and second_listen != [default]
        token = second.liveliness().declare_token(AgentInfo("second", "homebot/second", second_listen[0]).key)
        received: list[bytes] = []
        subscriber = watcher.declare_subscriber("homebot/second/agent/tree",
                                                lambda sample: received.append(sample.payload.to_bytes()))
        assert find_agents(watcher, 10.0, "second") == [AgentInfo("second", "homebot/second", second_listen[0])]
        publisher = second.declare_publisher("homebot/second/agent/tree")
        for _ in range(100):  # a peer not connected to the watcher's endpoint reaches it all the same
            publisher.put(b"{}")
            if received:
                break
            time.sleep(0.05)
        assert received
        subscriber.undeclare()
        token.undeclare()
    finally:
        for session in (watcher, second, first):
            session.close()


def _start_run(out: Path, listen: str, seed: int, budget: int, tick_period_s: float = 0.002) -> subprocess.Popen:
    """`homebot run` in the background; a long ``tick_period_s`` keeps it running until interrupted."""
    out.mkdir(parents=True)
    return subprocess.Popen(
        [sys.executable, "-m", "agent.app.cli", "run", "--seed", str(seed), "--listen", listen,
         "--set", f"episode.budget={budget}", "--set", f"episode.tick_period_s={tick_period_s}",
         "--stop", "budget", "--out", str(out)],
        stdout=open(out / "stdout.txt", "w"), stderr=open(out / "stderr.txt", "w"), stdin=subprocess.DEVNULL,
        preexec_fn=foreground_sigint,
    )


def _run_folder(out: Path) -> Path:
    [folder] = [path for path in out.iterdir() if path.is_dir()]
    return folder


def _wait_for_snapshots(out: Path, run: subprocess.Popen) -> Path:
    """The run folder once the tree has published snapshots (the episode is under way)."""
    for _ in range(1200):
        assert run.poll() is None, (out / "stderr.txt").read_text()
        snapshots = list(out.glob("*/snapshots.jsonl"))
        if snapshots and snapshots[0].stat().st_size:
            return snapshots[0].parent
        time.sleep(0.05)
    raise AssertionError(f"no snapshots under {out}")


def _watch(endpoint: str, *options: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "agent.app.cli", "watch", "--connect", endpoint, *options],
                          capture_output=True, text=True, timeout=120)


def test_two_runs_on_one_listen_endpoint_both_answer(tmp_path: Path) -> None:
    default = free_tcp_endpoint()
    runs = [_start_run(tmp_path / name, default, seed, 2) for name, seed in (("a", 2), ("b", 3))]
    try:
        codes = [run.wait(timeout=300) for run in runs]
    finally:
        for run in runs:
            run.kill()
    errors = [(tmp_path / name / "stderr.txt").read_text() for name in ("a", "b")]
    assert codes == [0, 0], errors
    results = [json.loads((_run_folder(tmp_path / name) / "result.json").read_text()) for name in ("a", "b")]
    assert [r["status"] for r in results] == ["answered", "answered"]
    moved = [r for r in results if r["listen"] != [default]]
    assert len(moved) == 1, results
    assert sum(f"{default} is taken" in error and moved[0]["listen"][0] in error for error in errors) == 1


def test_watch_lists_and_attaches_and_ctrl_c_interrupts(tmp_path: Path) -> None:
    default = free_tcp_endpoint()
    # a tick every half second: forty steps take minutes, so the episodes are still running at Ctrl-C
    runs = [_start_run(tmp_path / name, default, seed, 40, 0.5) for name, seed in (("a", 1), ("b", 4))]
    try:
        folders = [_wait_for_snapshots(tmp_path / name, run) for name, run in zip(("a", "b"), runs)]
        worlds = [psutil.Process(run.pid).children() for run in runs]
        listed = _watch(default, "--list", "--json")
        assert listed.returncode == 0, listed.stderr
        agents = {agent["run_id"]: agent for agent in json.loads(listed.stdout)}
        for folder in folders:
            result_listen = agents[folder.name]["endpoint"]
            assert agents[folder.name]["namespace"] == f"homebot/{folder.name}"
            assert result_listen.startswith("tcp/127.0.0.1:")
        assert sorted(agent["endpoint"] == default for agent in agents.values()) == [False, True]
        for folder in folders:  # the agent on the taken endpoint too, through the default one
            attached = _watch(default, "--run", folder.name, "--once", "--json", "--timeout", "60")
            assert attached.returncode == 0, attached.stderr
            assert json.loads(attached.stdout)["run"] == folder.name
        _inspect_attaches(default, folders[1].name)
        for run in runs:
            run.send_signal(signal.SIGINT)
        codes = [run.wait(timeout=120) for run in runs]
    finally:
        for run in runs:
            run.kill()
    assert codes == [130, 130]
    for name, folder, children in zip(("a", "b"), folders, worlds):
        stderr = (tmp_path / name / "stderr.txt").read_text()
        assert "Traceback" not in stderr and "interrupted" in stderr
        result = json.loads((folder / "result.json").read_text())
        assert result["status"] == "interrupted" and "SIGINT" in result["reason"]
        assert (folder / "map.png").exists()
        assert children and not any(child.is_running() and child.status() != psutil.STATUS_ZOMBIE
                                    for child in children)


def _inspect_attaches(endpoint: str, run_id: str) -> None:
    """`homebot inspect --run` serves the states of that run's agent, found through ``endpoint``."""
    port = int(free_tcp_endpoint().rsplit(":", 1)[1])
    inspector = subprocess.Popen([sys.executable, "-m", "agent.app.cli", "inspect", "--connect", endpoint, "--run", run_id,
                                  "--port", str(port), "--timeout", "60"], stdout=subprocess.PIPE,
                                 stderr=subprocess.PIPE, text=True)
    try:
        assert f"http://127.0.0.1:{port}/" in inspector.stdout.readline()
        info = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/api/info", timeout=10).read())
        assert info["mode"] == "live" and f"homebot/{run_id}" in info["source"]
        deadline = time.monotonic() + 60
        states: list = []
        while not states and time.monotonic() < deadline:
            states = json.loads(urllib.request.urlopen(f"http://127.0.0.1:{port}/api/states?from=0", timeout=10).read())["states"]
            time.sleep(0.5)
        assert states and {state["run"] for state in states} == {run_id}
    finally:
        inspector.terminate()
        inspector.wait(timeout=30)
