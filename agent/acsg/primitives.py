"""The names the executor asks the skill registry for: which skill does an action, which undoes it.

The scene graph speaks in action types ("open", "pick"); an `ActionNode` also carries the name of
the low-level primitive that does it, and that name is what `SkillCall.primitive` asks the skill
registry for (entry points ``homebot.skills`` in pyproject.toml: open_door, close_door,
open_drawer, close_drawer, pick_away, pick_back, move_camera, stow). This module is the one place
the acsg library spells those names.
"""

from __future__ import annotations

#: The paper's seven primitives (App. I-D); the names the executor is asked to run.
PRIMITIVES = ("open_door", "close_door", "open_drawer", "close_drawer", "pick_away", "pick_back", "move_camera")
#: What undoes a primitive, so exploration can leave the scene as it found it. ``open`` and
#: ``close`` stand for parts that are neither door nor drawer (a lid, a flap).
UNDO = {"open_door": "close_door", "open_drawer": "close_drawer", "open": "close", "pick_away": "pick_back"}
#: The primitive that moves an object out of the way (a "pick" action).
PICK_AWAY = "pick_away"


def open_primitive(part_label: str) -> str:
    """The primitive that opens a part, so that a door and a drawer each get their own skill.

    Args:
        part_label: the part's label.

    Returns:
        ``open_door`` or ``open_drawer`` for doors and drawers, ``open`` for anything else.
    """
    return f"open_{part_label}" if part_label in ("door", "drawer") else "open"


def action_primitive(action_type: str, target_label: str) -> str:
    """The primitive an action of ``action_type`` on an object runs when none is named.

    Args:
        action_type: the scene graph's action type ("open", "pick", ...).
        target_label: the label of the object acted on.

    Returns:
        `open_primitive` for "open", `PICK_AWAY` for "pick", else the type itself.
    """
    return {"open": open_primitive(target_label), "pick": PICK_AWAY}.get(action_type, action_type)

