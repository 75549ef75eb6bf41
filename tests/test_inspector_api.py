"""`homebot inspect`'s HTTP API over real runs: states of a recorded run, live states from the bus,
control requests checked and forwarded."""

from __future__ import annotations

import json
import time
import urllib.error
import urllib.request
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from inspector_runs import bus, clean_blackboard, live_run, record_run  # noqa: F401 - fixtures
from worlds.bus.keys import Keys
from agent.app.inspector.history import History
from agent.app.inspector.server import Inspector
from agent.app.inspector.sources import LiveAgent, load_run
from agent.app.tree_state import SnapshotError, behaviour_rows



def get(url: str) -> tuple[int, Any]:
    try:
        with urllib.request.urlopen(url, timeout=10) as reply:
            return reply.status, json.loads(reply.read())
    except urllib.error.HTTPError as error:
        return error.code, json.loads(error.read())


def post(url: str, body: bytes) -> tuple[int, Any]:
    request = urllib.request.Request(url, data=body, method="POST")
    try:
        with urllib.request.urlopen(request, timeout=10) as reply:
            return reply.status, json.loads(reply.read())
    except urllib.error.HTTPError as error:
        return error.code, json.loads(error.read())


@pytest.fixture
def recorded(tmp_path: Path) -> Iterator[str]:
    record_run(tmp_path / "run")
    history = History()
    load_run(tmp_path / "run", history)
    server = Inspector(history, {"mode": "recorded", "source": "run"}, result={"status": "failed"})
    try:
        yield server.start()
    finally:
        server.close()


def test_a_recorded_run_serves_every_tick_as_a_whole_state(recorded: str) -> None:
    status, info = get(recorded + "api/info")
    assert status == 200 and info == {"mode": "recorded", "source": "run", "controls": False}
    status, body = get(recorded + "api/states?from=0")
    states = body["states"]
    assert status == 200 and body["next"] == len(states) and [s["tick"] for s in states] == list(range(1, 7))
    first = {row["name"]: row for row in behaviour_rows(states[0])}
    last = {row["name"]: row for row in behaviour_rows(states[-1])}
    assert first["Count"]["status"] == "RUNNING" and first["Count"]["message"] == "5 to go"
    assert last["Check"]["status"] == "FAILURE" and last["Episode"]["status"] == "FAILURE"
    assert all(s["tree"] == states[0]["tree"] for s in states)
    assert {"tick": 2, "key": "/count", "by": "Count", "op": "set"} in states[1]["activity"]
    assert states[-1]["blackboard"]["/count"] == "0"
    assert get(recorded + "api/states?from=5")[1]["states"] == states[5:]
    assert get(recorded + "api/result")[1] == {"status": "failed"}


def test_a_recorded_run_pages_and_refusals(recorded: str) -> None:
    with urllib.request.urlopen(recorded, timeout=10) as reply:
        assert b'id="graph"' in reply.read()
    with urllib.request.urlopen(recorded + "static/vendor/dagre/dagre.min.js", timeout=10) as reply:
        assert reply.headers["Content-Type"].startswith("text/javascript")
    assert get(recorded + "api/states?from=-1") == (400, {"ok": False, "error": "from: expected a whole number ≥ 0"})
    assert get(recorded + "static/../server.py")[0] == 404
    assert get(recorded + "api/nothing")[0] == 404
    status, reply = post(recorded + "api/control/pause", b"{}")
    assert status == 409 and reply["error"].startswith("control:")


def test_the_event_stream_sends_each_state_with_its_position(recorded: str) -> None:
    with urllib.request.urlopen(recorded + "api/events?from=4", timeout=10) as stream:
        assert stream.headers["Content-Type"] == "text/event-stream"
        lines = [stream.readline().decode().strip() for _ in range(6)]
    assert lines[0] == "id: 4" and json.loads(lines[1].removeprefix("data: "))["tick"] == 5
    assert lines[3] == "id: 5" and json.loads(lines[4].removeprefix("data: "))["tick"] == 6


def test_a_run_folder_without_snapshots_or_with_a_bad_line_is_refused(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="RUN_DIR: no snapshots.jsonl"):
        load_run(tmp_path, History())
    (tmp_path / "snapshots.jsonl").write_text('{"version": 1}\n')
    with pytest.raises(SnapshotError, match="line 1: snapshot.version"):
        load_run(tmp_path, History())



def test_live_states_come_from_the_bus_and_control_goes_to_the_agent(bus: tuple[Any, Any]) -> None:
    agent_session, session = bus
    keys = Keys("homebot/inspected")
    requests: list[tuple[str, Any]] = []

    def answer(query: Any) -> None:
        request = json.loads(query.payload.to_bytes()) if query.payload else {}
        requests.append((str(query.key_expr), request))
        query.reply(query.key_expr, json.dumps({"ok": True, "paused": True, "tick": 3, "paused_before": None,
                                                "breakpoints": [], "faults": [], "injected": []}))

    queryable = agent_session.declare_queryable(keys.agent_control("pause"), answer)
    history = History()
    live = LiveAgent(session, None, history, timeout_s=2.0)
    server = Inspector(history, {"mode": "live", "source": "test"}, controller=live.control)
    url = server.start()
    try:
        thread = live_run(agent_session, keys.agent_tree, ticks=20, period_s=0.02)
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline and len(get(url + "api/states?from=0")[1]["states"]) < 5:
            time.sleep(0.05)
        states = get(url + "api/states?from=0")[1]["states"]
        assert len(states) >= 5 and states[-1]["tick"] > states[0]["tick"]
        assert live.namespace == "homebot/inspected"  # the first agent heard
        status, reply = post(url + "api/control/pause", b"")
        assert status == 200 and reply["ok"] and reply["paused"] and reply["tick"] == 3
        assert requests == [("homebot/inspected/agent/control/pause", {})]
        status, reply = post(url + "api/control/step", b"{}")
        assert status == 200 and not reply["ok"] and "no agent answers on homebot/inspected/agent/control/step" in reply["error"]
        assert post(url + "api/control/jump", b"{}") == (400, {"ok": False, "error": "verb: 'jump' is not one of "
                                                                "state, pause, continue, step, breakpoint, inject"})
        assert post(url + "api/control/pause", b"[1]")[1]["error"] == "body: expected a JSON object"
        assert post(url + "api/control/pause", b"{oops")[1]["error"].startswith("body: not UTF-8 JSON")
        thread.join(30)
    finally:
        server.close()
        live.close()
        queryable.undeclare()
