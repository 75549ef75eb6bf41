"""Small real runs for the inspector's tests: a tree ticked by the episode runner, its snapshots
logged to a run folder or published on the bus."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import py_trees
import pytest
from py_trees.common import Access, Status

from worlds.bus.session import free_tcp_endpoint, open_session
from agent.app.runtime.episode import EpisodeOutcome, EpisodeRunner
from agent.app.runtime.record import SnapshotLog

#: How long (s) a live run waits for something to listen to its snapshots before it ticks anyway.
MATCH_WAIT_S = 20.0


class Count(py_trees.behaviour.Behaviour):
    """RUNNING for ``ticks`` ticks, writing the count to the blackboard, then SUCCESS."""

    def __init__(self, name: str, ticks: int) -> None:
        super().__init__(name)
        self.left = ticks
        self.board = self.attach_blackboard_client(name=name)
        self.board.register_key("count", access=Access.WRITE)

    def update(self) -> Status:
        self.left -= 1
        self.board.count = self.left
        self.feedback_message = f"{self.left} to go"
        return Status.RUNNING if self.left > 0 else Status.SUCCESS


def tree(ticks: int) -> py_trees.behaviour.Behaviour:
    """A sequence: Count for ``ticks`` ticks, then a failing check (so the run's statuses change at the end).

    Args:
        ticks: how long Count runs.

    Returns:
        The tree.
    """
    return py_trees.composites.Sequence("Episode", memory=True, children=[
        Count("Count", ticks), py_trees.behaviours.Failure("Check")])


def record_run(folder: Path, ticks: int = 6) -> EpisodeOutcome:
    """Run the tree to its end, logging its snapshots to ``folder``/snapshots.jsonl.

    Args:
        folder: the run folder (made).
        ticks: how long Count runs.

    Returns:
        How it ended.
    """
    folder.mkdir(parents=True, exist_ok=True)
    py_trees.blackboard.Blackboard.clear()
    log = SnapshotLog(folder / "snapshots.jsonl")
    try:
        outcome = EpisodeRunner(tree(ticks), "recorded-run", [log], 10.0, max_wait_s=0.001).run()
    finally:
        log.close()
    (folder / "result.json").write_text(json.dumps({"status": outcome.status, "reason": outcome.reason}))
    return outcome


def live_run(session: Any, key: str, ticks: int, period_s: float) -> threading.Thread:
    """Tick the tree in a thread, publishing its snapshots on ``key`` once something listens there
    (or `MATCH_WAIT_S` have passed).

    Args:
        session: the bus session.
        key: where the snapshots go.
        ticks: how long Count runs.
        period_s: the time between ticks.

    Returns:
        The running thread.
    """
    publisher = session.declare_publisher(key)

    def run() -> None:
        try:
            # what listens may not have been matched yet: on two busy cores the ticks were over
            # before it heard any (the live test saw no state within 20 s)
            deadline = time.monotonic() + MATCH_WAIT_S
            while not publisher.matching_status.matching and time.monotonic() < deadline:
                time.sleep(0.01)
            EpisodeRunner(tree(ticks), "live-run", [lambda data: publisher.put(json.dumps(data))], 60.0,
                          tick_period_s=period_s, max_wait_s=period_s).run()
        finally:
            publisher.undeclare()

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


@pytest.fixture(autouse=True)
def clean_blackboard() -> Iterator[None]:
    """py_trees' blackboard is process-global: every test starts and ends with an empty one."""
    py_trees.blackboard.Blackboard.clear()
    yield
    py_trees.blackboard.Blackboard.clear()


@pytest.fixture
def bus() -> Iterator[tuple[Any, Any]]:
    """Two sessions on loopback: the agent's (listening) and the inspector's (connected to it)."""
    endpoint = free_tcp_endpoint()
    agent = open_session(listen=[endpoint])
    inspector = open_session(connect=[endpoint])
    try:
        yield agent, inspector
    finally:
        inspector.close()
        agent.close()
