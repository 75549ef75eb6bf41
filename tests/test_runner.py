"""The episode runner over small py_trees trees, its snapshots, and `homebot watch` over Zenoh."""

from __future__ import annotations

import io
import json
import threading
import time
from collections.abc import Iterator
from typing import Any

import numpy as np
import py_trees
import pytest
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from worlds.bus.keys import Keys
from worlds.bus.session import free_tcp_endpoint, open_session
from agent.app.runtime.episode import EpisodeOutcome, EpisodeRunner
from agent.app.runtime.readable import readable
from agent.app.runtime.snapshot import SNAPSHOT_VERSION
from agent.app.tree_state import SnapshotError, TreeState, behaviour_rows, fold, parse_snapshot
from agent.app.watch import render, watch

ROW_FIELDS = {"id", "name", "type", "parent", "status", "message", "visited"}


@pytest.fixture(autouse=True)
def clean_blackboard() -> Iterator[None]:
    """py_trees' blackboard is process-global: every test starts and ends with an empty one."""
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


class Boom(py_trees.behaviour.Behaviour):
    """Raises on its first tick."""

    def update(self) -> Status:
        raise RuntimeError("kaboom: the arm came off")


class FailWithMessage(py_trees.behaviour.Behaviour):
    def update(self) -> Status:
        self.feedback_message = "no floor in view"
        return Status.FAILURE


class Countdown(py_trees.behaviour.Behaviour):
    """RUNNING for ``ticks`` ticks with a message, then SUCCESS; writes a big array to the blackboard."""

    def __init__(self, name: str, ticks: int) -> None:
        super().__init__(name)
        self.left = ticks
        self.board = self.attach_blackboard_client(name=name)
        self.board.register_key("depth_image", access=Access.WRITE)
        self.board.register_key(bb.QUESTION, access=Access.WRITE)

    def update(self) -> Status:
        self.board.depth_image = np.zeros((480, 640), dtype=np.float32)
        self.board.set(bb.QUESTION, "What colour is the mug in the kitchen? " * 5)
        self.left -= 1
        self.feedback_message = f"{self.left} ticks to go"
        return Status.RUNNING if self.left > 0 else Status.SUCCESS


class Answer(py_trees.behaviour.Behaviour):
    """Writes the final answer to the blackboard."""

    def __init__(self, name: str = "Answer") -> None:
        super().__init__(name)
        self.board = self.attach_blackboard_client(name=name)
        self.board.register_key(bb.ANSWER, access=Access.WRITE)

    def update(self) -> Status:
        self.board.set(bb.ANSWER, {"rule": "confident", "letter": "B", "choice": "blue"})
        return Status.SUCCESS


def sequence(*children: py_trees.behaviour.Behaviour) -> py_trees.composites.Sequence:
    return py_trees.composites.Sequence("Episode", memory=True, children=list(children))


def run(root: py_trees.behaviour.Behaviour, sinks: list | None = None, max_seconds: float = 10.0) -> EpisodeOutcome:
    return EpisodeRunner(root, "run-test", sinks if sinks is not None else [], max_seconds, max_wait_s=0.001).run()


def test_raising_behaviour_fails_the_episode_with_its_name() -> None:
    outcome = run(sequence(py_trees.behaviours.Success("Ready"), Boom("Grasp mug")))
    assert outcome.status == "failed"
    assert outcome.failed_behaviour == "Grasp mug"
    assert "Grasp mug" in outcome.reason
    assert "RuntimeError" in outcome.reason and "kaboom: the arm came off" in outcome.reason
    assert outcome.answer is None
    assert outcome.ticks == 1


def test_raising_behaviour_inside_nested_composites_is_named() -> None:
    inner = py_trees.composites.Selector("Try", memory=False, children=[
        py_trees.behaviours.Failure("Nope"), Boom("Deep leaf")])
    outcome = run(sequence(Countdown("Warm up", 2), inner))
    assert outcome.status == "failed" and outcome.failed_behaviour == "Deep leaf"
    assert outcome.ticks == 2


def test_failing_leaf_reason_carries_its_feedback_message() -> None:
    outcome = run(sequence(py_trees.behaviours.Success("Ready"), FailWithMessage("Look at floor")))
    assert outcome.status == "failed"
    assert outcome.failed_behaviour == "Look at floor"
    assert "no floor in view" in outcome.reason
    assert outcome.reason.startswith("Look at floor")


def test_answer_on_the_blackboard_ends_the_episode_answered() -> None:
    outcome = run(sequence(Countdown("Explore", 3), Answer(), py_trees.behaviours.Running("Never reached")))
    assert outcome.status == "answered"
    assert outcome.reason == "confident"
    assert outcome.answer == {"rule": "confident", "letter": "B", "choice": "blue"}
    assert outcome.ticks == 3
    assert outcome.failed_behaviour is None


def test_forever_running_tree_stops_at_the_limit() -> None:
    started = time.monotonic()
    outcome = run(py_trees.behaviours.Running("Spin"), max_seconds=0.5)
    assert time.monotonic() - started < 10, "the runner did not stop"
    assert outcome.status == "failed"
    assert "limit" in outcome.reason and "0.5 s" in outcome.reason
    assert outcome.seconds >= 0.5
    assert outcome.ticks > 1


def test_snapshots_reach_the_sink() -> None:
    snapshots: list[dict[str, Any]] = []
    tree = sequence(Countdown("Explore", 3), Answer())
    outcome = run(tree, [snapshots.append])
    assert outcome.status == "answered"
    assert [s["tick"] for s in snapshots] == [1, 2, 3]
    assert snapshots[0]["full"] and "tree" in snapshots[0] and "tree" not in snapshots[1]
    names = {"Episode", "Explore", "Answer"}
    states = fold(snapshots)
    for snap, state in zip(snapshots, states):
        assert snap["version"] == SNAPSHOT_VERSION and snap["run"] == "run-test"
        rows = behaviour_rows(state)
        assert {b["name"] for b in rows} == names
        for behaviour in rows:
            assert set(behaviour) == ROW_FIELDS
            assert behaviour["status"] in {"SUCCESS", "FAILURE", "RUNNING", "INVALID"}
        json.dumps(snap)  # plain JSON
    by_name = {b["name"]: b for b in behaviour_rows(states[0])}
    assert by_name["Episode"]["parent"] is None
    assert by_name["Explore"]["parent"] == by_name["Episode"]["id"]
    assert by_name["Explore"]["type"] == "Countdown"
    assert by_name["Explore"]["message"] == "2 ticks to go"
    assert by_name["Explore"]["status"] == "RUNNING" and by_name["Explore"]["visited"]
    assert not by_name["Answer"]["visited"]
    assert states[0]["status"] == "RUNNING"
    assert by_name["Explore"]["id"] in snapshots[0]["visited"]
    last = {b["name"]: b for b in behaviour_rows(states[-1])}
    assert last["Answer"]["visited"] and last["Answer"]["status"] == "SUCCESS"


def test_only_ticks_that_change_something_are_published() -> None:
    snapshots: list[dict[str, Any]] = []
    waiting = py_trees.behaviours.Running("Wait")
    outcome = run(sequence(Countdown("Explore", 2), py_trees.behaviours.Success("Ready"), waiting),
                  [snapshots.append], max_seconds=0.3)
    assert outcome.status == "failed" and outcome.ticks > 5
    ticks = [s["tick"] for s in snapshots]
    assert ticks[:3] == [1, 2, 3] and ticks[-1] == outcome.ticks  # the first, each change, the last
    assert len(ticks) < outcome.ticks / 2
    later = [s for s in snapshots[3:-1] if not s.get("full")]
    assert all(not s["behaviours"] and not s["blackboard"] for s in later)
    assert fold(snapshots)[-1]["behaviours"] == fold(snapshots[:3])[-1]["behaviours"]


def test_snapshots_carry_changed_texts_and_who_wrote_them() -> None:
    snapshots: list[dict[str, Any]] = []
    run(sequence(Countdown("Explore", 2), Answer()), [snapshots.append])
    board = snapshots[0]["blackboard"]
    assert all(isinstance(v, str) and len(v) <= 72 for v in board.values())
    depth_key = next(k for k in board if k.endswith("depth_image"))
    assert "[480, 640]" in board[depth_key] and "float32" in board[depth_key]
    question_key = next(k for k in board if k.endswith(bb.QUESTION))
    assert board[question_key].startswith("'What colour is the mug") and board[question_key].endswith("…")
    assert not any(k.endswith("depth_image") for k in snapshots[1]["blackboard"])  # same text: not sent again
    assert {"tick": 1, "key": depth_key, "by": "Explore", "op": "init"} in snapshots[0]["activity"]
    assert {"tick": 2, "key": depth_key, "by": "Explore", "op": "set"} in snapshots[1]["activity"]
    answer_key = next(k for k in snapshots[-1]["blackboard"] if k.endswith(bb.ANSWER))
    assert {"tick": 2, "key": answer_key, "by": "Answer", "op": "init"} in snapshots[-1]["activity"]
    assert py_trees.blackboard.Blackboard.activity_stream is None  # the runner turned it off again


def test_readable_describes_large_values_briefly() -> None:
    big = np.zeros((1000, 1000, 3))
    text = readable(big)
    assert "[1000, 1000, 3]" in text and "float64" in text and len(text) < 72
    assert readable(list(range(1000))).startswith("list of 1000, last 999")
    assert readable("x" * 500).endswith("…") and len(readable("x" * 500)) == 72
    assert readable(3.5) == "3.5" and readable("hi") == "'hi'"
    assert readable(EpisodeOutcome("answered", "r", None, 1, 0.1)).startswith("EpisodeOutcome(status='answered'")
    assert readable(b"x" * 1000) == "<bytes of 1000>"
    assert readable(np.array([1.23456, 2.0])) == "array [1.235, 2.0]"


def test_readable_texts_of_observations_maps_and_poses() -> None:
    from agent.mapping.occupancy import ExplorationMap
    from agent.mapping.camera import Intrinsics
    from agent.observation import Observation
    from agent.pose import Pose2D

    assert readable(Pose2D(1.0, 2.5, np.pi / 2)) == "(1.00, 2.50, 90°)"
    observation = Observation(np.zeros((48, 64, 3), np.uint8), np.zeros((48, 64), np.float32),
                              np.zeros((48, 64), np.int32), (), Intrinsics(64, 48, 50.0, 50.0, 32.0, 24.0),
                              np.eye(4), Pose2D(1.0, 2.0, 0.0))
    assert readable(observation) == "64×48 image at (1.00, 2.00, 0°), 0 labels"
    text = readable(ExplorationMap((0.0, 0.0)))
    assert text.startswith("map ") and " m from (" in text and "cell " in text and "revision 0" in text
    assert readable([Pose2D(0, 0, 0)] * 9) == "list of 9, last (0.00, 0.00, 0°)"


def test_a_raising_sink_does_not_end_the_episode() -> None:
    def broken(snapshot: dict[str, Any]) -> None:
        raise OSError("disk full")

    snapshots: list[dict[str, Any]] = []
    outcome = run(sequence(Countdown("Explore", 3), Answer()), [broken, snapshots.append])
    assert outcome.status == "answered"
    assert [s["tick"] for s in snapshots] == [1, 2, 3]


# --- rendering and parsing snapshots -----------------------------------------------------------


def first_snapshot() -> dict[str, Any]:
    snapshots: list[dict[str, Any]] = []
    run(sequence(Countdown("Explore", 2), FailWithMessage("Look at floor")), [snapshots.append])
    return snapshots[0]


def test_render_shows_every_behaviour_and_message() -> None:
    snap = TreeState().apply(first_snapshot())
    text = render(snap, colour=False)
    for behaviour in snap["tree"]:
        assert behaviour["name"] in text
    assert "1 ticks to go" in text
    assert "run run-test" in text and "tick 1" in text
    assert "\x1b[" not in text
    lines = text.splitlines()
    explore = next(line for line in lines if "Explore" in line)
    episode = next(line for line in lines if "Episode" in line)
    assert explore.startswith("    ") and not episode.startswith(" ")  # children are indented
    assert "blackboard" in text and "tick 1: Explore init /depth_image" in text
    assert "\x1b[" in render(snap, colour=True)


def test_render_includes_later_messages() -> None:
    snapshots: list[dict[str, Any]] = []
    run(sequence(py_trees.behaviours.Success("Ready"), FailWithMessage("Look at floor")), [snapshots.append])
    text = render(fold(snapshots)[-1], colour=False)
    assert "Look at floor" in text and "no floor in view" in text


def test_parse_snapshot_round_trip_and_rejections() -> None:
    snap = first_snapshot()
    assert parse_snapshot(json.dumps(snap).encode()) == snap
    for bad in (b"not json", b"\xff\xfe", b""):
        with pytest.raises(SnapshotError, match="not UTF-8 JSON"):
            parse_snapshot(bad)
    for bad, field in ((b"[1, 2]", "JSON object"), (b'{"version": 1}', "snapshot.version"),
                       (json.dumps({**snap, "behaviours": "all"}).encode(), "snapshot.behaviours"),
                       (json.dumps({**snap, "tick": "3"}).encode(), "snapshot.tick"),
                       (json.dumps({**snap, "behaviours": {"x": ["RUNNING"]}}).encode(), "snapshot.behaviours.x"),
                       (json.dumps({k: v for k, v in snap.items() if k != "tree"}).encode(), "snapshot.tree")):
        with pytest.raises(SnapshotError, match=field):
            parse_snapshot(bad)


# --- watch over Zenoh --------------------------------------------------------------------------


def publish_until(session: Any, key: str, payloads: list[bytes], stop: threading.Event) -> threading.Thread:
    """Put ``payloads`` on ``key`` over and over until ``stop``: the subscriber may come up late."""
    publisher = session.declare_publisher(key)

    def loop() -> None:
        try:
            while not stop.is_set():
                for payload in payloads:
                    publisher.put(payload)
                time.sleep(0.02)
        finally:
            publisher.undeclare()

    thread = threading.Thread(target=loop, daemon=True)
    thread.start()
    return thread


@pytest.fixture
def sessions() -> Iterator[tuple[Any, Any]]:
    endpoint = free_tcp_endpoint()
    agent = open_session(listen=[endpoint])
    watcher = open_session(connect=[endpoint])
    try:
        yield agent, watcher
    finally:
        watcher.close()
        agent.close()


@pytest.mark.parametrize("namespace", [None, "homebot/watch-test"])
def test_watch_prints_a_published_snapshot(sessions: tuple[Any, Any], namespace: str | None) -> None:
    agent, watcher = sessions
    snap = first_snapshot()
    stop = threading.Event()
    thread = publish_until(agent, Keys("homebot/watch-test").agent_tree, [json.dumps(snap).encode()], stop)
    out = io.StringIO()
    try:
        code = watch(watcher, namespace, once=True, as_json=True, timeout_s=5, out=out)
    finally:
        stop.set()
        thread.join(5)
    assert code == 0
    assert json.loads(out.getvalue()) == TreeState().apply(snap)
    assert out.getvalue().count("\n") == 1


def test_watch_skips_bad_snapshots(sessions: tuple[Any, Any], capsys: pytest.CaptureFixture[str]) -> None:
    agent, watcher = sessions
    snap = first_snapshot()
    stop = threading.Event()
    thread = publish_until(agent, Keys("homebot/bad").agent_tree, [b"garbage", json.dumps(snap).encode()], stop)
    out = io.StringIO()
    try:
        code = watch(watcher, "homebot/bad", once=True, as_json=False, timeout_s=5, out=out)
    finally:
        stop.set()
        thread.join(5)
    assert code == 0
    assert "Explore" in out.getvalue() and "1 ticks to go" in out.getvalue()
    assert "garbage" not in out.getvalue()


def test_watch_returns_1_when_nothing_arrives(sessions: tuple[Any, Any], capsys: pytest.CaptureFixture[str]) -> None:
    _, watcher = sessions
    out = io.StringIO()
    started = time.monotonic()
    assert watch(watcher, "homebot/silent", once=True, as_json=True, timeout_s=0.5, out=out) == 1
    assert time.monotonic() - started < 10
    assert out.getvalue() == ""
    assert "no tree snapshot on homebot/silent/agent/tree" in capsys.readouterr().err


def test_watch_ignores_other_namespaces(sessions: tuple[Any, Any], capsys: pytest.CaptureFixture[str]) -> None:
    agent, watcher = sessions
    stop = threading.Event()
    thread = publish_until(agent, Keys("homebot/other").agent_tree, [json.dumps(first_snapshot()).encode()], stop)
    out = io.StringIO()
    try:
        code = watch(watcher, "homebot/mine", once=True, as_json=True, timeout_s=1.0, out=out)
    finally:
        stop.set()
        thread.join(5)
    assert code == 1 and out.getvalue() == ""
