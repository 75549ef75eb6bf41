"""The example skill, Stow, tested like the primitives: through the real world server over Zenoh."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
import zenoh

from worlds.bus.keys import Keys
from worlds.bus.link import WorldLink
from skills.context import SkillContext
from skills.running import run_to_end
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlanError
from skills.primitives import LookAt
from skills.registry import SkillRegistry
from skills.stow import Stow


@pytest.fixture
def link(world: tuple[zenoh.Session, Keys]) -> Iterator[WorldLink]:
    session, keys = world
    link = WorldLink(session, keys, timeout_s=20.0)
    link.call("reset", {"seed": 0, "tabletop": "drawer-only"})
    yield link
    link.close()


def test_stow_folds_the_arm_back_after_a_look(link: WorldLink) -> None:
    assert link.call("arm_state").meta["stowed"]
    context = SkillContext(link)
    looked = run_to_end(LookAt(context, bindings={"look_point": (0.0, 0.0, 0.8)}), timeout_s=60)
    assert looked.ok, looked.reason
    assert not link.call("arm_state").meta["stowed"]
    stowed = run_to_end(Stow(context, bindings={"surface_z": 0.75}), timeout_s=60)  # the table top: keep clear of it
    assert stowed.ok, stowed.reason
    assert link.call("arm_state").meta["stowed"]
    assert SkillRegistry().load("stow") is Stow


def test_a_goal_outside_the_limits_is_refused_by_name(link: WorldLink) -> None:
    planner = ArmPlanner.from_description(link.describe().wait().meta)
    with pytest.raises(SkillPlanError, match="outside the joint limits"):
        planner.plan_joint_move(planner.stowed, (0.0, -1.0, 0.0), [9.0] * planner.kin.dof)
    with pytest.raises(SkillPlanError, match="expected 8 finite joint values"):
        planner.plan_joint_move(planner.stowed, (0.0, -1.0, 0.0), [0.0, 1.0])
