"""The act branch: the robot opens the storage a question asks about and the VLM sees inside."""

from __future__ import annotations

import math
import time
from dataclasses import replace

import py_trees
import pytest
from py_trees.common import Access, Status

from agent import blackboard as bb
from agent.observation import Observation
from agent.runtime.local_world import local_world
from agent.runtime.world_link import WorldLink
from behaviours.look_inside import LookInside, storage_in_question
from worlds.home import generate_home
from worlds.scenario import make_scenario


@pytest.mark.parametrize("question, storage", [
    ("Is there any milk carton in the fridge in the kitchen?", "fridge"),
    ("What is inside the drawer chest in the bedroom?", "drawer chest"),
    ("What is inside the cabinet in the bathroom?", "cabinet"),
    ("What colour is the cabinet in the kitchen?", None),  # about the cabinet, not what is in it
    ("Is the cup on the counter?", None),
    ("How many cups are there in the kitchen?", None),
])
def test_the_storage_a_question_asks_what_is_in(question: str, storage: str | None) -> None:
    assert storage_in_question(question) == storage


@pytest.fixture
def board() -> py_trees.blackboard.Client:
    client = py_trees.blackboard.Client(name="test")
    for key in (bb.QUESTION, bb.OBSERVATION, bb.ACTS):
        client.register_key(key, access=Access.WRITE)
    yield client
    py_trees.blackboard.Blackboard.clear()


def _tick(behaviour: LookInside, timeout_s: float = 240.0) -> Status:
    deadline = time.monotonic() + timeout_s
    behaviour.tick_once()
    while behaviour.status == Status.RUNNING:
        assert time.monotonic() < deadline, "LookInside still running"
        time.sleep(0.05)
        behaviour.tick_once()
    return behaviour.status


@pytest.mark.slow
def test_the_robot_opens_the_cabinet_the_question_names_and_the_view_shows_its_contents(board) -> None:
    seed = 3
    home = generate_home(seed)
    scenario = make_scenario(home, seed, hidden=True)
    assert scenario.question == "What is inside the cabinet in the bathroom?" and scenario.answer_text == "basket"
    [cabinet] = [f for f in home.furniture if f.room == scenario.target["room"] and f.category == "cabinet"]
    x, y, _ = cabinet.center
    facing = (x + 1.6 * math.cos(cabinet.facing), y + 1.6 * math.sin(cabinet.facing), cabinet.facing + math.pi)
    with local_world() as served:
        link = WorldLink(served.session, served.keys, timeout_s=60.0)
        link.call("reset", {"seed": seed, "scenario": replace(scenario, start_pose=facing).to_dict()})
        first = Observation.from_message(link.call("observe", {}))
        assert "basket" not in {label.category for label in first.labels}  # hidden behind the door
        board.set(bb.QUESTION, scenario.question)
        board.set(bb.OBSERVATION, first)
        behaviour = LookInside(link)
        assert _tick(behaviour) == Status.SUCCESS, behaviour.feedback_message
        inside = board.get(bb.OBSERVATION)
        assert inside is not first and "basket" in {label.category for label in inside.labels}
        [act] = board.get(bb.ACTS)
        assert act["storage"] == "cabinet" and act["outcome"].startswith("opened the cabinet's door")
        # the same door is not opened twice: with nothing else to open, the next tick fails and says why
        board.set(bb.OBSERVATION, first)
        assert _tick(behaviour) == Status.FAILURE and "no unopened cabinet" in behaviour.feedback_message
        link.close()


def test_a_question_about_no_storage_fails_at_once_saying_so(board) -> None:
    board.set(bb.QUESTION, "How many cups are there in the kitchen?")
    behaviour = LookInside(link=None)  # type: ignore[arg-type]  # never reached: nothing to open
    assert _tick(behaviour, 5.0) == Status.FAILURE
    assert behaviour.feedback_message == "the question asks about no storage"
