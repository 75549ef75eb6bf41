"""Reading the world's replies to arm commands: the arm's state, and whether a step went as planned.

Pure functions of the reply, so the rules an `skills.base.ArmSkill` applies to every step (a move
that stopped on a contact, fell short, lost what it held; a grasp that caught the wrong thing; a
part that did not open far enough) test without a world.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from skills.arm.skill_plan import Step
from worlds.vocabulary import FURNITURE, STORAGE_CATEGORIES

#: A move that ends further than this (rad or m, any joint) from its last sample was held back.
BLOCKED_RAD = 0.03
#: A move held back with its TCP this near (m) its target has arrived as near as the memory's
#: voxels place anything: a finger brushing the handle it closes around, a carried thing grazing a
#: neighbour at the end of the carry. What follows is re-timed from where the arm is.
ARRIVED_M = 0.015
#: The share of a planned opening or closing the part must make for the skill to count it done.
MIN_PART_SHARE = 0.6
#: What furniture the world labels its bodies as (tables, cabinets, chests): never a thing to pick.
_FURNITURE = frozenset({*FURNITURE, *STORAGE_CATEGORIES})
#: The ``robot_link`` of a contact the world reports for what the hand carries (docs/bus.md).
HELD_CONTACT = "held object"
#: What a grasp holds when it holds what the step expects, and what it says otherwise.
_EXPECTED = {
    "handle": (lambda label: label.get("category") == "handle", "not a handle"),
    # a carcass or a table has no part link either: a fingertip brought down onto a box's top in a
    # cabinet stopped on the cabinet instead, and closed on nothing (recursive 1043 of tuning-wide)
    "object": (lambda label: label.get("link") is None and label.get("category") not in _FURNITURE,
               "part of a piece of furniture, not an object"),
    # lowering what the hand carries: it arrives where that meets what it is put on (a drawer's
    # bottom, reported as the carried thing's contact; a table, not reported at all); the arm
    # itself touching anything is no arrival
    "support": (lambda label: label.get("robot_link") == HELD_CONTACT, "the arm itself, not what it carries"),
    # backing off what the hand let go of, the work done: it arrives where a touch too light to
    # report holds it back (the forearm against the door it opened, 1.6 cm short: the door was
    # pushed shut again, occlusion 1030 of tuning-wide); a contact the world reports is no arrival
    "clear": (lambda label: False, "a contact on the way back"),
}


def arm_state(meta: dict[str, Any]) -> dict[str, Any]:
    """The fields of an arm reply, checked: joints, TCP pose, held, stowed, and a motion's errors and contacts.

    Args:
        meta: the reply's metadata.

    Returns:
        The fields, with the joints and TCP pose as arrays.

    Raises:
        ValueError: a field is missing or malformed.
    """
    try:
        q = np.asarray(meta["positions"], dtype=float)
        tcp = np.asarray(meta["tcp_pose"], dtype=float)
    except (KeyError, TypeError, ValueError) as error:
        raise ValueError(f"arm reply: missing or malformed {error}") from None
    if q.ndim != 1 or tcp.shape != (4, 4) or not (np.all(np.isfinite(q)) and np.all(np.isfinite(tcp))):
        raise ValueError("arm reply: positions must be a vector and tcp_pose a finite 4x4 matrix")
    held = meta.get("held")
    return {
        "q": q,
        "tcp_pose": tcp,
        "held": held if isinstance(held, dict) else None,
        "gripper_width": float(meta.get("gripper_width", 0.0)),
        "stowed": bool(meta.get("stowed", False)),
        "final_error": float(meta.get("final_error", 0.0)),
        "stopped_on_contact": bool(meta.get("stopped_on_contact", False)),
        "contacts": [c for c in meta.get("contacts", []) if isinstance(c, dict)],
    }


def thing_name(label: dict[str, Any]) -> str:
    """How a reply's label reads in a message: "handle 12".

    Args:
        label: a reply's label (its ``category`` and ``id``).

    Returns:
        The name.
    """
    return f"{label.get('category', 'something')} {label.get('id', '')}".strip()


def touched_names(contacts: list[dict[str, Any]]) -> str:
    """What a move touched, in words: each thing with the robot link that touched it.

    Args:
        contacts: the contacts of an arm_trajectory reply.

    Returns:
        "drawer 12 (held object), handle 9 (panda_hand)", or "something" for none.
    """
    return ", ".join(f"{thing_name(c)} ({c.get('robot_link')})" for c in contacts) or "something"


def step_problem(step: Step, state: dict[str, Any], previous: dict[str, Any] | None) -> tuple[str, float | None]:
    """Why the world's reply to ``step`` means the skill failed, and how far a part it moved stands.

    Args:
        step: the step the reply answers.
        state: the reply, read by `arm_state`.
        previous: the arm's state before the step (None for the first).

    Returns:
        The problem ("" when the step went as planned) and, for a step that moves a door or
        drawer, the part's opening where the hand ended (m or rad; None for other steps).
    """
    held = state["held"]
    if step.kind == "gripper":
        return _gripper_problem(step, state), None
    contacts = state["contacts"]
    stopped = state["stopped_on_contact"] or state["final_error"] > BLOCKED_RAD
    carrying = step.touch != "support" or held is not None
    if step.touch and stopped and carrying and all(_EXPECTED[step.touch][0](c) for c in contacts):
        return "", None  # a touch's approach found what it reaches for (or a touch too light to report)
    if state["stopped_on_contact"]:
        return f"stopped on contact with {touched_names(contacts)}", None
    if step.part_motion is not None:
        motion = step.part_motion
        achieved = motion.opening(state["tcp_pose"][:3, 3])
        want = motion.end - motion.start
        kind = motion.geometry.kind
        if previous is not None and previous["held"] is not None and held is None:
            return f"the gripper lost the {kind}'s handle", achieved
        if (achieved - motion.start) / want < MIN_PART_SHARE:
            verb = "open" if want > 0 else "close"
            return (f"the {kind} did not {verb}: its handle went {abs(achieved - motion.start):.3f} "
                    f"{motion.unit} of the {abs(want):.3f} {motion.unit} planned"), achieved
        return "", achieved
    if state["final_error"] > BLOCKED_RAD and _short_of(step, state) > ARRIVED_M:
        short = f"the arm stopped {state['final_error']:.3f} rad short of its target"
        if contacts:  # a move that does not stop on contact pressed on against it
            return f"{short}: held back against {touched_names(contacts)}", None
        return f"{short}: something held it back (a touch too light for the world to report as a contact)", None
    if previous is not None and previous["held"] is not None and held is None:
        return f"the gripper lost {thing_name(previous['held'])}", None
    return "", None


def _short_of(step: Step, state: dict[str, Any]) -> float:
    """How far (m) the TCP ended from where ``step`` was to take it; inf when the step names no target."""
    if step.tcp_target is None:
        return float("inf")
    return float(np.linalg.norm(np.asarray(step.tcp_target)[:3, 3] - state["tcp_pose"][:3, 3]))


def _gripper_problem(step: Step, state: dict[str, Any]) -> str:
    """Why a gripper step's reply is wrong: closing caught nothing, or the wrong thing, or
    something it should not have; opening still holds."""
    held = state["held"]
    if step.action == "close" and step.expect_held is None:
        return "" if held is None else f"the fingers caught {thing_name(held)} closing before the approach"
    if step.action == "close":
        if held is None:
            return f"the gripper closed on nothing ({state['gripper_width'] * 1000:.0f} mm between the fingers)"
        expected, otherwise = _EXPECTED[step.expect_held]
        if not expected(held):
            return f"the gripper holds {thing_name(held)}, {otherwise}"
    elif held is not None:
        return f"the gripper still holds {thing_name(held)} after opening"
    return ""
