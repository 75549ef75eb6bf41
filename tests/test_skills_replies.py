"""Reading the world's replies to arm steps (`skills.replies.step_problem`), from plain replies."""

from __future__ import annotations

import numpy as np
import pytest

from skills.arm.skill_plan import Step
from skills.replies import ARRIVED_M, BLOCKED_RAD, HELD_CONTACT, step_problem


def _reply(final_error: float = 0.0, contacts: tuple = (), stopped: bool = False, held: dict | None = None,
           at: tuple = (0.0, 0.0, 0.0)) -> dict:
    tcp = np.eye(4)
    tcp[:3, 3] = at
    return {"q": np.zeros(8), "tcp_pose": tcp, "held": held, "gripper_width": 0.0, "stowed": False,
            "final_error": final_error, "stopped_on_contact": stopped, "contacts": list(contacts)}


CARRIED = {"category": "jar", "id": 9}


@pytest.mark.parametrize("touch, reply, problem", [
    # lowering what the hand carries arrives where it is held back by what it is put on
    ("support", _reply(final_error=2 * BLOCKED_RAD, held=CARRIED), ""),
    # ... but not where the arm itself touched something
    ("support", _reply(final_error=2 * BLOCKED_RAD, stopped=True, held=CARRIED,
                       contacts=({"category": "drawer", "id": 4, "link": 1, "robot_link": "panda_hand"},)),
     "stopped on contact with drawer 4 (panda_hand)"),
    # ... and where what it carries met a drawer's bottom, which the world reports as its contact
    ("support", _reply(final_error=2 * BLOCKED_RAD, stopped=True, held=CARRIED,
                       contacts=({"category": "drawer", "id": 4, "link": 1, "robot_link": HELD_CONTACT},)), ""),
    # ... nor where what it carried was lost on the way
    ("support", _reply(final_error=2 * BLOCKED_RAD), "short of its target"),
    # any other move held back so is short of its target
    (None, _reply(final_error=2 * BLOCKED_RAD, held=CARRIED), "a touch too light for the world to report"),
    (None, _reply(final_error=BLOCKED_RAD / 2, held=CARRIED), ""),
])
def test_a_lowering_held_back_by_what_it_carries_has_arrived(touch, reply, problem) -> None:
    step = Step("move", "lower", samples=np.zeros((3, 8)), dt=0.01, touch=touch)
    found, achieved = step_problem(step, reply, _reply(held=CARRIED))
    assert achieved is None
    assert (found == "") if problem == "" else (problem in found)


@pytest.mark.parametrize("short_m, arrived", [(0.01, True), (0.03, False)])
def test_a_move_held_back_within_a_voxel_of_its_target_has_arrived(short_m: float, arrived: bool) -> None:
    target = np.eye(4)
    target[:3, 3] = (0.5, 0.0, 0.9)
    step = Step("move", "approach the door handle", samples=np.zeros((3, 8)), dt=0.01, stop_on_contact=True,
                tcp_target=target)
    reply = _reply(final_error=2 * BLOCKED_RAD, at=(0.5 - short_m, 0.0, 0.9))
    found, _ = step_problem(step, reply, _reply())
    assert (found == "") == arrived and (arrived or "a touch too light" in found)
    assert ARRIVED_M == pytest.approx(0.015)


HANDLE = {"category": "handle", "id": 12, "link": 3, "robot_link": "panda_leftfinger"}


@pytest.mark.parametrize("touch, contacts, problem", [
    # backing off a handle let go of, held back by a touch too light to report: the work is done
    ("clear", (), ""),
    # ... but a contact the world reports on the way back is named
    ("clear", (HANDLE,), "held back against handle 12 (panda_leftfinger)"),
    # any other move held back is short of its target, and says against what where it can
    (None, (), "a touch too light for the world to report"),
    (None, (HANDLE,), "held back against handle 12 (panda_leftfinger)"),
])
def test_a_back_off_held_back_by_a_light_touch_has_arrived(touch, contacts, problem) -> None:
    target = np.eye(4)
    target[:3, 3] = (0.5, 0.0, 0.9)
    step = Step("move", "back off the door handle", samples=np.zeros((3, 8)), dt=0.01, tcp_target=target,
                touch=touch)
    reply = _reply(final_error=2 * BLOCKED_RAD, contacts=contacts, at=(0.5, -0.05, 0.9))
    found, _ = step_problem(step, reply, _reply())
    assert (found == "") if problem == "" else (problem in found and "short of its target" in found)


@pytest.mark.parametrize("touched, problem", [
    ({"category": "box", "id": 5, "link": None, "robot_link": "panda_rightfinger"}, ""),
    # the fingertips came down on the cabinet's board, not the box on it: no arrival
    ({"category": "cabinet", "id": 2, "link": None, "robot_link": "panda_rightfinger"},
     "stopped on contact with cabinet 2 (panda_rightfinger)"),
    ({"category": "drawer", "id": 4, "link": 1, "robot_link": "panda_leftfinger"}, "stopped on contact with drawer 4"),
])
def test_fingertips_brought_down_onto_an_object_arrive_only_on_an_object(touched: dict, problem: str) -> None:
    step = Step("move", "down onto the object", samples=np.zeros((3, 8)), dt=0.01, stop_on_contact=True, touch="object")
    found, _ = step_problem(step, _reply(final_error=2 * BLOCKED_RAD, stopped=True, contacts=(touched,)), _reply())
    assert (found == "") if problem == "" else (problem in found)
