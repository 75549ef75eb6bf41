"""Running one skill to its end, for callers that wait for it (the scene-graph executor, scripts)."""

from __future__ import annotations

import logging
import threading
import time

from py_trees.common import Status

from skills.base import SkillResult
from skills.ports import PortedSkill

log = logging.getLogger(__name__)


def run_to_end(skill: PortedSkill, timeout_s: float = 120.0, tick_s: float = 0.05) -> SkillResult:
    """Set ``skill`` up, tick it until it has finished, and say how it went.

    The skill is ticked on its own, not in a tree: its inputs are the values it was made with (or
    the blackboard keys it is bound to), and its result is read from its ``result`` output, so
    nothing is shared with a tree that runs beside it. Between ticks it waits for the wake handed
    to its ``setup`` (an arm skill's world replies call it), at most ``tick_s``.

    Args:
        skill: a skill made with its ports bound, not yet set up.
        timeout_s: how long it may run.
        tick_s: the longest wait between ticks when nothing wakes it.

    Returns:
        Its ``result`` output; for a skill without one, success or failure with its feedback
        message. A tick that raises, or a skill still running after ``timeout_s``, gives a failed
        result saying so.
    """
    deadline = time.monotonic() + timeout_s
    name = skill.skill_name or skill.name
    woken = threading.Event()
    skill.setup(wake=woken.set)
    while True:
        woken.clear()  # a reply from here on, during the tick too, ends the wait after it
        try:
            skill.tick_once()
        except Exception as error:  # a bug in a tick: fail with it rather than hang
            log.exception("%s raised", name)
            skill.stop(Status.INVALID)
            return SkillResult(False, f"{name}: {type(error).__name__}: {error}", name)
        if skill.status != Status.RUNNING:
            break
        if time.monotonic() > deadline:
            skill.stop(Status.INVALID)
            return SkillResult(False, f"{name}: still running after {timeout_s:.0f} s", name)
        woken.wait(tick_s)
    result = skill.outputs.get("result")
    if not isinstance(result, SkillResult):
        ok = skill.status == Status.SUCCESS
        result = SkillResult(ok, "" if ok else skill.feedback_message, name)
    return result
