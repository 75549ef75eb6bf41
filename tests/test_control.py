"""The control protocol: pause, step, breakpoints and injected faults, on plain threads, on small
trees, and against whole episodes over real Zenoh."""

from __future__ import annotations

import json
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import py_trees
import pytest
import zenoh

from worlds.bus.keys import Keys
from worlds.bus.session import free_tcp_endpoint, open_session
from agent.app.cli import main
from agent.app.config import load_config
from agent.app.control_client import ControlFailed, send
from agent.app.runtime.control import ControlRefused, EpisodeControl
from agent.app.runtime.control_bus import answer, parse_request
from agent.app.runtime.episode import EpisodeRunner
from agent.app.runtime.run import RunRequest, run_episode

SETTLE_S = 30.0  # generous: a test only waits this long when something is broken


@pytest.fixture(autouse=True)
def clean_blackboard() -> Iterator[None]:
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


def _ticker(control: EpisodeControl, ticks: int, behaviours: tuple[str, ...], done: list[int]) -> threading.Thread:
    """A thread that ticks like the runner: ``ticks`` ticks, each asking before ``behaviours``."""
    def run() -> None:
        for n in range(1, ticks + 1):
            control.before_tick()
            for name in behaviours:
                control.before_behaviour(name)
            done.append(n)
            control.after_tick(n)
        control.finish()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def test_a_paused_ticker_waits_steps_one_tick_and_continues() -> None:
    control, done = EpisodeControl(["Look"]), []
    control.pause()
    thread = _ticker(control, 3, ("Look",), done)
    control.pause(SETTLE_S)  # returns once the ticker waits
    assert done == [] and control.state()["paused"] and control.state()["tick"] == 0
    control.step(SETTLE_S)
    assert done == [1]
    assert control.state() == {"paused": True, "tick": 1, "paused_before": None, "breakpoints": [],
                               "faults": [], "injected": []}
    control.resume()
    thread.join(SETTLE_S)
    assert done == [1, 2, 3] and not control.state()["paused"] and control.paused_s > 0


def test_a_breakpoint_stops_before_its_behaviour_and_a_step_finishes_the_tick() -> None:
    control, done = EpisodeControl(["Look", "Move"]), []
    control.set_breakpoint("Move", True)
    thread = _ticker(control, 2, ("Look", "Move"), done)
    control.pause(SETTLE_S)  # already stopping at the breakpoint: waits until it does
    state = control.state()
    assert state["paused"] and state["paused_before"] == "Move" and state["tick"] == 0 and done == []
    assert state["breakpoints"] == ["Move"]
    control.step(SETTLE_S)  # the rest of tick 1, then a pause between ticks
    assert done == [1] and control.state()["paused_before"] is None and control.state()["paused"]
    control.set_breakpoint("Move", False)
    control.resume()
    thread.join(SETTLE_S)
    assert done == [1, 2]


def test_a_fault_is_taken_once_and_recorded() -> None:
    control = EpisodeControl(["Look", "Move"])
    control.inject("Move", "raise")
    assert control.state()["faults"] == [{"behaviour": "Move", "fault": "raise"}]
    control.after_tick(4)
    assert control.before_behaviour("Look") is None
    assert control.before_behaviour("Move") == {"tick": 5, "behaviour": "Move", "fault": "raise"}
    assert control.before_behaviour("Move") is None
    assert control.state()["faults"] == [] and control.injected == [{"tick": 5, "behaviour": "Move", "fault": "raise"}]


def test_bad_control_calls_are_refused_naming_the_field() -> None:
    control = EpisodeControl(["Look", "Move"])
    with pytest.raises(ControlRefused, match=r"^step: the episode is not paused"):
        control.step()
    with pytest.raises(ControlRefused, match=r"^breakpoint\.behaviour: 'Fly' is not a behaviour of the tree; "
                                             r"its behaviours: Look, Move$"):
        control.set_breakpoint("Fly", True)
    with pytest.raises(ControlRefused, match=r"^inject\.fault: expected one of failure, raise, got 'crash'"):
        control.inject("Look", "crash")
    with pytest.raises(ControlRefused, match=r"^inject\.behaviour: expected a behaviour's name"):
        control.inject(["Look"], "raise")  # type: ignore[arg-type]
    assert control.state()["faults"] == [] and control.state()["breakpoints"] == []


@pytest.mark.parametrize(("verb", "payload", "error"), [
    ("jump", b"{}", "verb: 'jump' is not one of state, pause, continue, step, breakpoint, inject"),
    ("pause", b'{"now": true}', "pause.now: unknown field; pause takes no fields"),
    ("breakpoint", b'{"behaviour": "Look"}', "breakpoint.on: missing"),
    ("breakpoint", b'{"behaviour": "Look", "on": 1}', "breakpoint.on: expected true or false, got 1"),
    ("inject", b'{"behaviour": "Look", "fault": "raise", "when": 3}', "inject.when: unknown field; inject takes behaviour, fault"),
    ("inject", b"\xff{", "inject: the request is not UTF-8 JSON"),
    ("state", b"[1, 2]", "state: the request must be a JSON object, got list"),
    ("state", b"[" * 50_000, "state: the request is not UTF-8 JSON"),
])
def test_bad_requests_are_refused_naming_the_field(verb: str, payload: bytes, error: str) -> None:
    control = EpisodeControl(["Look"])
    with pytest.raises(ControlRefused) as refused:
        parse_request(verb, payload)
    assert str(refused.value).startswith(error)
    reply = answer(control, verb, payload)
    assert reply["ok"] is False and reply["error"].startswith(error)


def test_a_good_request_replies_with_the_state() -> None:
    control = EpisodeControl(["Look"])
    assert parse_request("state", None) == {} and parse_request("pause", b"") == {}
    reply = answer(control, "breakpoint", b'{"behaviour": "Look", "on": true}')
    assert reply == {"ok": True, "paused": False, "tick": 0, "paused_before": None, "breakpoints": ["Look"],
                     "faults": [], "injected": []}


class Grasp(py_trees.behaviour.Behaviour):
    """RUNNING forever, counting its updates."""

    def __init__(self) -> None:
        super().__init__("Grasp")
        self.updates = 0

    def update(self) -> py_trees.common.Status:
        self.updates += 1
        return py_trees.common.Status.RUNNING


def _tree() -> tuple[py_trees.behaviour.Behaviour, Grasp]:
    grasp = Grasp()
    return py_trees.composites.Sequence("Fetch", memory=True, children=[
        py_trees.behaviours.Success("Ready"), grasp]), grasp


@pytest.mark.parametrize("target", ["Grasp", "Fetch"])
def test_an_injected_failure_fails_the_behaviour_without_running_it(target: str) -> None:
    root, grasp = _tree()
    control = EpisodeControl(b.name for b in root.iterate())
    runner = EpisodeRunner(root, "run-test", [], 10.0, tick_period_s=0.001, control=control)
    outcome: list = []
    thread = threading.Thread(target=lambda: outcome.append(runner.run()), daemon=True)
    control.pause()
    thread.start()
    control.pause(SETTLE_S)
    control.step(SETTLE_S)  # tick 1: Grasp runs
    assert grasp.updates == 1 and grasp.status == py_trees.common.Status.RUNNING
    control.inject(target, "failure")
    control.step(SETTLE_S)  # tick 2: the fault, and the tree fails
    thread.join(SETTLE_S)
    assert grasp.updates == 1 and grasp.status != py_trees.common.Status.RUNNING
    assert outcome[0].status == "failed" and outcome[0].ticks == 2
    assert control.injected == [{"tick": 2, "behaviour": target, "fault": "failure"}]
    if target == "Grasp":
        assert outcome[0].failed_behaviour == "Grasp" and outcome[0].reason == "Grasp: injected failure"
    else:
        assert root.feedback_message == "injected failure"


def test_an_injected_raise_ends_the_episode_naming_the_behaviour() -> None:
    root, grasp = _tree()
    runner = EpisodeRunner(root, "run-test", [], 10.0, tick_period_s=0.001)
    runner.control.inject("Grasp", "raise")
    outcome = runner.run()
    assert outcome.status == "failed" and outcome.failed_behaviour == "Grasp" and grasp.updates == 0
    assert outcome.reason == "Grasp raised InjectedFault: injected into Grasp on tick 1"


# Whole episodes over real Zenoh.


def _episode_config(endpoint: str) -> Any:
    return load_config(overrides=[f'bus.listen=["{endpoint}"]', "episode.budget=50", "stop.rule=budget"])


def _wait_for_agent(session: zenoh.Session, namespace: str | None, process: subprocess.Popen | None = None,
                    thread: threading.Thread | None = None) -> dict[str, Any]:
    """The first reply to ``state`` once the agent's tree is up."""
    deadline = time.monotonic() + 180
    while time.monotonic() < deadline:
        if (process is not None and process.poll() is not None) or (thread is not None and not thread.is_alive()):
            raise AssertionError("the episode ended before its control answered")
        try:
            return send(session, namespace, "state", timeout_s=2.0)
        except ControlFailed:
            time.sleep(0.2)
    raise AssertionError("the agent's control never answered")


def _raw(session: zenoh.Session, key: str, payload: bytes) -> dict[str, Any]:
    replies = [json.loads(r.ok.payload.to_bytes()) for r in session.get(key, payload=payload, timeout=10.0) if r.ok]
    assert len(replies) == 1
    return replies[0]


def _until(session: zenoh.Session, namespace: str, done: Any) -> dict[str, Any]:
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        state = send(session, namespace, "state")
        if done(state):
            return state
        time.sleep(0.05)
    raise AssertionError(f"the agent never got there; last state {state}")


@pytest.mark.slow
def test_pause_step_breakpoint_and_an_injected_failure_in_a_real_episode(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    endpoint, namespace = free_tcp_endpoint(), "homebot/control-a"
    result: dict[str, Any] = {}
    request = RunRequest(seed=2, config=_episode_config(endpoint), out_root=tmp_path, run_id="control-a")
    episode = threading.Thread(target=lambda: result.update(run_episode(request)), daemon=True)
    session = open_session(connect=[endpoint])
    episode.start()
    try:
        _wait_for_agent(session, namespace, thread=episode)
        paused = send(session, namespace, "pause")
        assert paused["ok"] and paused["paused"] and paused["paused_before"] is None
        ticks = paused["tick"]
        assert [send(session, namespace, "state")["tick"] for _ in range(2)] == [ticks, ticks]

        stepped = send(session, namespace, "step")
        assert stepped["ok"] and stepped["paused"] and stepped["tick"] == ticks + 1
        assert send(session, namespace, "state")["tick"] == ticks + 1

        assert send(session, namespace, "breakpoint", {"behaviour": "Navigate", "on": True})["breakpoints"] == ["Navigate"]
        send(session, namespace, "continue")
        at_navigate = _until(session, namespace, lambda s: s["paused_before"] == "Navigate")
        assert main(["watch", "--state", "--connect", endpoint]) == 0  # the one agent, found without --namespace
        assert f"paused before Navigate, {at_navigate['tick']} ticks done" in capsys.readouterr().out

        refused = _raw(session, Keys(namespace).agent_control("breakpoint"), b'{"behaviour": "Fly", "on": true}')
        assert refused["ok"] is False and refused["error"].startswith("breakpoint.behaviour: 'Fly' is not a behaviour")
        assert "Navigate" in refused["error"] and "Observe" in refused["error"]
        assert _raw(session, Keys(namespace).agent_control("pause"), b'{"now": 1}')["error"].startswith("pause.now:")
        assert _raw(session, Keys(namespace).agent_control("inject"), b"not json")["error"].startswith(
            "inject: the request is not UTF-8 JSON")
        assert _raw(session, Keys(namespace).agent_control("jump"), b"{}")["error"].startswith("verb: 'jump'")
        assert main(["watch", "--inject", "Fly=failure", "--connect", endpoint, "--namespace", namespace]) == 1
        assert "inject.behaviour: 'Fly'" in capsys.readouterr().err

        assert main(["watch", "--unbreak", "Navigate", "--connect", endpoint, "--namespace", namespace]) == 0
        assert main(["watch", "--inject", "Observe=failure", "--connect", endpoint, "--namespace", namespace]) == 0
        assert "pending faults: Observe=failure" in capsys.readouterr().out
        assert main(["watch", "--continue", "--json", "--connect", endpoint, "--namespace", namespace]) == 0
        assert json.loads(capsys.readouterr().out)["paused"] is False
        episode.join(120)
    finally:
        if episode.is_alive():  # end it however it stands
            send(session, namespace, "inject", {"behaviour": "EQA episode", "fault": "raise"})
            send(session, namespace, "continue")
            episode.join(60)
        session.close()
    assert result["status"] == "failed"
    assert result["failed_behaviour"] == "Observe" and result["reason"] == "Observe: injected failure"
    recorded = json.loads((tmp_path / "control-a" / "result.json").read_text())
    assert [(i["behaviour"], i["fault"]) for i in recorded["injected"]] == [("Observe", "failure")]
    assert recorded["injected"][0]["tick"] > at_navigate["tick"]


@pytest.mark.slow
def test_an_injected_raise_fails_a_command_line_episode_naming_the_behaviour(tmp_path: Path) -> None:
    endpoint = free_tcp_endpoint()
    run = subprocess.Popen(
        [sys.executable, "-m", "agent.app.cli", "run", "--seed", "1", "--listen", endpoint, "--out", str(tmp_path),
         "--set", "episode.budget=50", "--stop", "budget"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    session = open_session(connect=[endpoint])
    try:
        _wait_for_agent(session, None, process=run)
        assert main(["watch", "--inject", "IntegrateMap=raise", "--connect", endpoint]) == 0
        stdout, stderr = run.communicate(timeout=120)
    finally:
        run.kill()
        session.close()
    assert run.returncode == 1
    assert "IntegrateMap raised InjectedFault: injected into IntegrateMap on tick" in stderr
    folder = Path(stdout.split("run folder:")[1].strip())
    recorded = json.loads((folder / "result.json").read_text())
    assert recorded["status"] == "failed" and recorded["failed_behaviour"] == "IntegrateMap"
    assert [(i["behaviour"], i["fault"]) for i in recorded["injected"]] == [("IntegrateMap", "raise")]
