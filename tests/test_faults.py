"""Faults reported as they are, by a real `homebot run` against a real world process over Zenoh on
loopback: a world killed mid-episode or at start-up is gone (with its exit code, and at start-up the
end of its log), a frozen one is alive but silent, and joining a world that is not there says why
within seconds: nothing listens at the port, or the worlds there serve under other namespaces."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import psutil
import pytest

from worlds.bus.keys import Keys
from worlds.bus.liveness import LivenessWatch
from worlds.bus.session import free_tcp_endpoint, open_session

pytestmark = pytest.mark.slow

#: Longer than any test here may take: a start-up timeout a fault must not wait out.
NEVER_S = "600"

#: This checkout, ahead of any installed copy, for the processes the tests start.
ENV = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(Path(__file__).resolve().parent.parent),
                                                                os.environ.get("PYTHONPATH")]))}


def _run(tmp_path: Path, *args: str) -> subprocess.Popen:
    """`homebot run` in its own process group, listening on a free port, its folders under ``tmp_path``."""
    return subprocess.Popen([sys.executable, "-m", "agent.app.cli", "run", "--out", str(tmp_path / "runs"),
                             "--listen", free_tcp_endpoint(), "--set", f"bus.world_start_timeout_s={NEVER_S}", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True, env=ENV)


def _world_of(run: subprocess.Popen, timeout_s: float = 120.0) -> psutil.Process:
    """The world process ``run`` started (or its worker did), as soon as it is there."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        assert run.poll() is None, run.communicate()[1][-2000:]
        for child in psutil.Process(run.pid).children(recursive=True):
            try:
                if "worlds.server" in child.cmdline():
                    return child
            except psutil.NoSuchProcess:
                continue
        time.sleep(0.005)
    raise AssertionError("the run started no world")


def _mid_episode(run: subprocess.Popen, tmp_path: Path, timeout_s: float = 240.0) -> None:
    """Wait until ``run``'s tree has published a few snapshots: the episode is under way."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        assert run.poll() is None, run.communicate()[1][-2000:]
        logs = list((tmp_path / "runs").glob("*/snapshots.jsonl"))
        if logs and len(logs[0].read_text().splitlines()) >= 3:
            return
        time.sleep(0.1)
    raise AssertionError("the episode never got under way")


def _ended(run: subprocess.Popen, timeout_s: float = 60.0) -> tuple[int, str]:
    """``run``'s exit code and stderr; it must end well within ``timeout_s``."""
    try:
        _, stderr = run.communicate(timeout=timeout_s)
    except subprocess.TimeoutExpired:
        os.killpg(run.pid, signal.SIGKILL)
        raise AssertionError(f"the run did not end within {timeout_s:g} s") from None
    return run.returncode, stderr


def _result(tmp_path: Path) -> dict:
    [path] = (tmp_path / "runs").glob("*/result.json")
    return json.loads(path.read_text())


def test_a_world_killed_mid_episode_is_gone_and_the_run_ends(tmp_path: Path) -> None:
    run = _run(tmp_path, "--seed", "0")
    world = _world_of(run)
    _mid_episode(run, tmp_path)
    world.kill()
    code, stderr = _ended(run)
    gone = "the world process is gone (it was killed by SIGKILL (exit code -9))"
    assert code == 1 and gone in stderr and "Traceback" not in stderr, stderr
    result = _result(tmp_path)
    assert result["status"] == "failed" and gone in result["reason"], result["reason"]


def test_a_frozen_world_is_alive_but_did_not_answer(tmp_path: Path) -> None:
    run = _run(tmp_path, "--seed", "0", "--set", "bus.query_timeout_s=3", "--set", "bus.move_timeout_s=3")
    world = _world_of(run)
    _mid_episode(run, tmp_path)
    world.suspend()
    try:
        code, stderr = _ended(run)
    finally:
        if world.is_running():
            world.resume()
    assert code == 1 and "Traceback" not in stderr, stderr
    reason = _result(tmp_path)["reason"]
    assert "the world is alive but did not answer within 3.0 s" in reason and "nobody serves" not in reason, reason
    assert not world.is_running() or world.status() == psutil.STATUS_ZOMBIE, "the stopped world was left behind"


def test_a_world_killed_at_start_up_leaves_its_exit_code_and_its_log(tmp_path: Path) -> None:
    run = _run(tmp_path, "--seed", "0")
    _world_of(run).kill()  # while it still imports: before it could announce itself
    code, stderr = _ended(run)
    assert code == 1 and "Traceback" not in stderr, stderr
    assert "the episode could not start: the world process ended before it came up: it was killed by SIGKILL " \
           "(exit code -9)" in stderr, stderr
    tail = stderr.split("the end of its log", 1)[1]
    assert "-m worlds.server --namespace" in tail and "(the world wrote nothing before it ended)" in tail, tail
    assert "SIGKILL" in _result(tmp_path)["reason"]


def test_joining_a_port_nobody_listens_on_is_connection_refused(tmp_path: Path) -> None:
    endpoint = free_tcp_endpoint()
    run = _run(tmp_path, "--connect", endpoint)
    code, stderr = _ended(run)
    assert code == 1 and "Traceback" not in stderr, stderr
    assert f"connection refused at {endpoint}" in stderr, stderr
    assert f"connection refused at {endpoint}" in _result(tmp_path)["reason"]


def test_a_port_that_opens_while_the_join_settles_is_waited_for_not_refused(tmp_path: Path) -> None:
    """A world started beside its agent may open its port a moment after the agent first looks: a
    refused connection is final only once it has lasted `JOIN_SETTLE_S`."""
    import socket
    import threading

    from agent.app.config import load_config
    from agent.app.runtime.episode_bus import JOIN_SETTLE_S, EpisodeBus
    from agent.app.runtime.request import RunRequest
    from agent.app.runtime.world_process import WorldStartError

    endpoint = free_tcp_endpoint()
    port = int(endpoint.rsplit(":", 1)[1])
    listener = socket.socket()
    listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    opener = threading.Timer(JOIN_SETTLE_S / 3, lambda: (listener.bind(("127.0.0.1", port)), listener.listen()))
    config = load_config(overrides=[f"bus.listen=[\"{free_tcp_endpoint()}\"]"])
    bus = EpisodeBus.open(RunRequest(seed=0, config=config, out_root=tmp_path, connect=endpoint))
    try:
        opener.start()
        with pytest.raises(WorldStartError) as raised:
            bus.wait_ready(JOIN_SETTLE_S + 1.0)  # a plain socket, not a world: no token ever comes
    finally:
        opener.join()
        bus.close()
        listener.close()
    assert "connection refused" not in str(raised.value)
    assert f"no world answers under 'homebot/default' at {endpoint} within" in str(raised.value)


def test_joining_under_a_namespace_no_world_serves_names_the_visible_worlds(tmp_path: Path) -> None:
    endpoint = free_tcp_endpoint()
    world = subprocess.Popen([sys.executable, "-m", "worlds.server", "--namespace", "homebot/elsewhere",
                              "--listen", endpoint], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=ENV)
    try:
        with open_session(connect=[endpoint]) as session:
            watch = LivenessWatch(session, Keys("homebot/elsewhere").world_alive)
            assert watch.wait_alive(120.0), "the world never came up"
            watch.close()
        run = _run(tmp_path, "--connect", endpoint, "--namespace", "homebot/here")
        code, stderr = _ended(run)
    finally:
        world.terminate()
        world.wait(30)
    assert code == 1 and "Traceback" not in stderr, stderr
    assert f"no world answers under 'homebot/here' at {endpoint}: the worlds visible serve under " \
           "'homebot/elsewhere'" in stderr, stderr


def test_an_evaluation_whose_world_is_killed_fails_that_episode_and_goes_on_in_a_new_world(tmp_path: Path) -> None:
    from worlds.suite import plan_split, write_suite

    suite = write_suite(tmp_path / "suite", plan_split(3, [3], 73000, ("suite",)), hidden=False)["suite"]
    out = tmp_path / "out"
    evaluation = subprocess.Popen([sys.executable, "-m", "agent.app.cli", "eval", "explore", "--suite", str(suite),
                                   "--workers", "1", "--methods", "fbe", "--out", str(out), "--record",
                                   "--listen", free_tcp_endpoint(), "--set", "episode.budget=30"],
                                  stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True,
                                  env=ENV)
    deadline = time.monotonic() + 240
    snapshots = out / "recordings" / "suite-0000-fbe" / "snapshots.jsonl"
    while not snapshots.exists() or len(snapshots.read_text().splitlines()) < 3:
        assert evaluation.poll() is None, evaluation.communicate()[1][-2000:]
        assert time.monotonic() < deadline, "the first episode never got under way"
        time.sleep(0.1)
    _world_of(evaluation).kill()
    code, stderr = _ended(evaluation, 600)
    assert code == 0 and "Traceback" not in stderr, stderr
    results = {line["id"]: line for line in map(json.loads, (out / "explore-results.jsonl").read_text().splitlines())}
    assert "the world process is gone (it was killed by SIGKILL (exit code -9))" in results["suite-0000"]["reason"]
    assert results["suite-0001"]["status"] == results["suite-0002"]["status"] == "answered", results


def test_the_faults_bench_reports_each_fault_with_its_reason() -> None:
    bench = subprocess.run([sys.executable, "-m", "agent.app.cli", "bench", "faults", "--repeats", "1", "--json"],
                           capture_output=True, text=True, timeout=600, env=ENV)
    assert bench.returncode == 0, bench.stderr[-2000:]
    reasons = {name: row["reason"] for name, row in json.loads(bench.stdout)["faults"].items()}
    assert "the world process is gone (it was killed by SIGKILL" in reasons["killed"]
    assert "the world is alive but did not answer within 2.0 s" in reasons["frozen"]
    assert "connection refused at tcp/127.0.0.1:" in reasons["closed port"]
    assert "the worlds visible serve under 'homebot/bench-elsewhere'" in reasons["other namespace"]
    assert reasons["ctrl-c run"].startswith("exit code 130: homebot run: interrupted")
