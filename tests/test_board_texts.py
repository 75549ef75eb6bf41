"""Snapshots render a blackboard key again only when its value may have changed, and still show
every change: a value replaced, one changed in place by the leaf that got it for writing, and one
a RUNNING leaf changes through an object it holds without touching the board."""

from __future__ import annotations

from typing import Any

import py_trees
from py_trees.common import Access, Status

from agent.app.runtime.board_texts import BoardTexts
from agent.app.runtime.episode import EpisodeRunner
from agent.app.runtime.readable import readable
from agent.app.tree_state import fold
from inspector_runs import clean_blackboard  # noqa: F401 - an autouse fixture

LOG = "/log"


class Grow(py_trees.behaviour.Behaviour):
    """Gets the log for writing and appends to it in place; succeeds at once."""

    def __init__(self) -> None:
        super().__init__("Grow")
        self.board = self.attach_blackboard_client(name="Grow")
        self.board.register_key(LOG, access=Access.WRITE)

    def update(self) -> Status:
        if not self.board.exists(LOG):
            self.board.set(LOG, [])
        self.board.get(LOG).append(len(self.board.get(LOG)))
        return Status.SUCCESS


class Hold(py_trees.behaviour.Behaviour):
    """Gets the log once, then appends to the list it holds on later ticks, RUNNING for ``ticks``
    ticks, as a worker of the leaf would: the board sees no write after the first."""

    def __init__(self, ticks: int) -> None:
        super().__init__("Hold")
        self.left = ticks
        self.held: list[int] = []
        self.board = self.attach_blackboard_client(name="Hold")
        self.board.register_key(LOG, access=Access.WRITE)

    def initialise(self) -> None:
        self.board.set(LOG, self.held)

    def update(self) -> Status:
        self.held.append(len(self.held))
        self.left -= 1
        return Status.RUNNING if self.left > 0 else Status.SUCCESS


class Done(py_trees.behaviour.Behaviour):
    """Ends the episode after ``ticks`` ticks, writing the answer."""

    def __init__(self, ticks: int) -> None:
        super().__init__("Done")
        self.left = ticks
        self.board = self.attach_blackboard_client(name="Done")
        self.board.register_key("/answer", access=Access.WRITE)

    def update(self) -> Status:
        self.left -= 1
        if self.left > 0:
            return Status.RUNNING
        self.board.set("/answer", {"rule": "confident", "letter": "A"})
        return Status.SUCCESS


def _boards(root: py_trees.behaviour.Behaviour) -> tuple[list[dict[str, str]], list[dict[str, str]]]:
    """Each snapshot's whole board, and every key rendered afresh at that moment."""
    snapshots: list[dict[str, Any]] = []
    fresh: list[dict[str, str]] = []

    def sink(data: dict[str, Any]) -> None:
        snapshots.append(data)
        fresh.append({key: readable(value) for key, value in py_trees.blackboard.Blackboard.storage.items()})

    outcome = EpisodeRunner(root, "run-test", [sink], 10.0, max_wait_s=0.001).run()
    assert outcome.status == "answered"
    return [state["blackboard"] for state in fold(snapshots)], fresh


def test_a_value_changed_in_place_by_the_leaf_that_got_it_for_writing_shows() -> None:
    root = py_trees.composites.Sequence("Episode", memory=False, children=[Grow(), Done(4)])
    shown, fresh = _boards(root)
    assert [board[LOG] for board in shown] == ["[0]", "[0, 1]", "[0, 1, 2]", "[0, 1, 2, 3]"]
    assert shown == fresh


def test_a_value_a_running_leaf_changes_without_the_board_shows() -> None:
    root = py_trees.composites.Sequence("Episode", memory=True, children=[Hold(3), Done(2)])
    shown, fresh = _boards(root)
    assert [board[LOG] for board in shown] == ["[0]", "[0, 1]", "[0, 1, 2]", "[0, 1, 2]"]
    assert shown == fresh


def test_texts_are_kept_for_unchanged_values_and_made_for_new_ones() -> None:
    texts = BoardTexts()
    log: list[int] = [1]
    assert texts.texts({LOG: log, "/n": 3}, None) == {LOG: "[1]", "/n": "3"}
    log.append(2)  # unseen: nobody said the key changed
    assert texts.texts({LOG: log, "/n": 4}, set()) == {LOG: "[1]", "/n": "4"}  # another object: made again
    assert texts.texts({LOG: log}, {LOG}) == {LOG: "[1, 2]"}  # said to have changed
