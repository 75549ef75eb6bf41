"""A tree that waits ticks again when what it waits for is in: the runner neither spins nor sleeps
a fixed time between ticks. The runners here wait up to an hour when nothing wakes them, so an
episode that ends at all was woken, and the tick counts say how often the tree ticked."""

from __future__ import annotations

import threading
from typing import Any

import py_trees
from py_trees.common import Access, Status

from agent.app.runtime.episode import EpisodeOutcome, EpisodeRunner
from agent.vlm.backends import make_vlm
from agent.vlm.settings import VLMSettings
from behaviours import blackboard as bb
from behaviours.async_vlm import AsyncVLMQuery
from behaviours.world_command import WorldCommand
from worlds.bus.codec import Message
from worlds.bus.keys import Keys
from worlds.bus.link import WorldLink
from worlds.bus.rpc import CommandServer
from worlds.bus.session import free_tcp_endpoint, open_session
from inspector_runs import clean_blackboard  # noqa: F401 - an autouse fixture

HOUR_S = 3600.0  # the longest the runners here wait unwoken: far longer than any test runs
SETTLE_S = 30.0  # generous: a test only waits this long when something is broken


class Answer(py_trees.behaviour.Behaviour):
    """Writes an answer, which ends the episode."""

    def __init__(self) -> None:
        super().__init__("Answer")
        self.board = self.attach_blackboard_client(name="Answer")
        self.board.register_key(bb.ANSWER, access=Access.WRITE)

    def update(self) -> Status:
        self.board.set(bb.ANSWER, {"rule": "confident", "letter": "A"})
        return Status.SUCCESS


class Probe(WorldCommand):
    """Sends ``probe`` to the world and succeeds on its reply."""

    def on_reply(self, message: Message) -> Status:
        return Status.SUCCESS


class Ask(AsyncVLMQuery):
    """Asks in the worker until the test lets the answer out."""

    def __init__(self, release: threading.Event) -> None:
        super().__init__("Ask", make_vlm(VLMSettings()), timeout_s=HOUR_S, timer=None)
        self.release = release

    def ask(self, *inputs: Any) -> str:
        self.release.wait(SETTLE_S)
        return "A"

    def use(self, answer: Any) -> Status:
        return Status.SUCCESS


def _episode(root: py_trees.behaviour.Behaviour) -> tuple[EpisodeRunner, list[EpisodeOutcome], threading.Thread,
                                                          threading.Event]:
    """A runner that waits up to an hour between ticks, running ``root`` in a thread; the event is
    set once tick 1 is over (its snapshot published)."""
    ticked = threading.Event()
    runner = EpisodeRunner(root, "run-test", [lambda data: ticked.set()], HOUR_S, max_wait_s=HOUR_S)
    outcome: list[EpisodeOutcome] = []
    thread = threading.Thread(target=lambda: outcome.append(runner.run()), daemon=True)
    thread.start()
    return runner, outcome, thread, ticked


def test_the_worlds_reply_wakes_the_waiting_tree() -> None:
    """Tick 1 sends the command and finds no reply; the reply wakes tick 2, which answers."""
    endpoint = free_tcp_endpoint()
    world, agent = open_session(listen=[endpoint]), open_session(connect=[endpoint])
    keys = Keys(f"test/wake{endpoint.rsplit(':', 1)[1]}")
    asked, release, stop = threading.Event(), threading.Event(), threading.Event()

    def gated(message: Message) -> tuple[dict[str, Any], dict]:
        asked.set()
        release.wait(SETTLE_S)
        return {}, {}

    server = CommandServer(world, keys.namespace)
    server.add(keys.world_cmd("probe"), gated)
    serving = threading.Thread(target=server.serve, args=(stop,), daemon=True)
    serving.start()
    link = WorldLink(agent, keys)
    try:
        token = world.liveliness().declare_token(keys.world_alive)
        assert link.liveness.wait_alive(SETTLE_S)
        root = py_trees.composites.Sequence("Episode", memory=True, children=[Probe("Probe", link, "probe"), Answer()])
        _, outcome, thread, ticked = _episode(root)
        assert asked.wait(SETTLE_S) and ticked.wait(SETTLE_S), "tick 1 never sent the command"
        release.set()
        thread.join(SETTLE_S)
        assert outcome and outcome[0].status == "answered" and outcome[0].ticks == 2
        token.undeclare()
    finally:
        release.set()
        stop.set()
        serving.join(SETTLE_S)
        server.close()
        link.close()
        agent.close()
        world.close()


def test_the_vlms_answer_wakes_the_waiting_tree() -> None:
    """Tick 1 asks and finds no answer; the answer wakes tick 2, which answers."""
    release = threading.Event()
    root = py_trees.composites.Sequence("Episode", memory=True, children=[Ask(release), Answer()])
    _, outcome, thread, ticked = _episode(root)
    assert ticked.wait(SETTLE_S)
    release.set()
    thread.join(SETTLE_S)
    assert outcome and outcome[0].status == "answered" and outcome[0].ticks == 2


def test_control_requests_reach_a_tree_that_waits_on_nothing() -> None:
    """A leaf RUNNING on nothing that wakes the tree: pause, step and an injected fault still act
    at once, each a tick, not after the hour the runner would wait."""
    root = py_trees.composites.Sequence("Episode", memory=True, children=[py_trees.behaviours.Running("Wait")])
    runner, outcome, thread, ticked = _episode(root)
    control = runner.control
    assert ticked.wait(SETTLE_S)
    control.pause(SETTLE_S)
    assert control.state()["paused"] and control.state()["tick"] == 1
    control.step(SETTLE_S)
    assert control.state()["paused"] and control.state()["tick"] == 2
    control.inject("Wait", "failure")
    control.resume()
    thread.join(SETTLE_S)
    assert outcome and outcome[0].status == "failed" and outcome[0].ticks == 3
