"""Why a pick away is refused before the arm moves: where no place is free within the arm's reach of
a thing that no stand brings within reach either, the reason says how far out the thing stands, and
the evaluation counts it beyond the arm's reach rather than short of idle space."""

from __future__ import annotations

import math
import re

import pytest

from agent.app.eval.failure_causes import action_cause
from agent.pose import Pose2D
from skills.arm.skill_plan import SkillPlanError
from skills.robot import Robot
from test_robot_keep_off import NoWorld, _remember


def _table_full_before(box_y: float) -> tuple[Robot, object]:
    """A robot before the front (y = -0.1) of a table 2.4 m across and 2 m deep, 0.35 m from it,
    whose top is taken up to y = 0.8 by a tray, and a box standing on the table at ``box_y``."""
    robot = Robot(NoWorld())  # type: ignore[arg-type]
    robot.body.home = Pose2D(0.0, -0.45, math.pi / 2)
    _remember(robot, "table", (0.0, 0.9, 0.745), (2.4, 2.0, 0.02))
    _remember(robot, "tray", (0.0, 0.35, 0.8), (2.4, 0.9, 0.1))
    box = _remember(robot, "box", (0.0, box_y, 0.8), (0.1, 0.1, 0.1))
    return robot, box


def test_no_free_place_for_a_thing_beyond_reach_says_how_far_out_it_stands() -> None:
    robot, box = _table_full_before(0.9)  # 1.35 m from the front's and the back's stands, 1.55 m from the sides'
    with pytest.raises(SkillPlanError) as refused:
        robot.picks.pick_away(box)
    reason = str(refused.value)
    assert reason.startswith("idle spot: no free place"), reason
    assert re.search(r"\(1\.3[56] m from the base's axis, beyond the arm's reach over a table, 0\.85 m\)$", reason), reason
    assert action_cause(f"pick_away box (o{box.id}) FAILED: {reason}")[1] == "beyond the arm's reach"


def test_no_free_place_for_a_thing_within_reach_is_short_of_idle_space() -> None:
    robot, box = _table_full_before(0.2)  # on the tray's far part: 0.65 m out, and no place free in reach
    with pytest.raises(SkillPlanError) as refused:
        robot.picks.pick_away(box)
    reason = str(refused.value)
    assert reason.startswith("idle spot: no free place") and "beyond" not in reason, reason
    assert action_cause(f"pick_away box (o{box.id}) FAILED: {reason}")[1] == "no idle space"
