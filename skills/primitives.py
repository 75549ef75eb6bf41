"""The seven arm primitives of RoboEXP as behaviours: open and close doors and drawers, pick an
object away to an idle spot and back, and move the wrist camera to look at a point.

Each is a small `skills.base.ArmSkill`: what it needs from the `SkillTarget` on the blackboard, and
which `skills.arm.plan.ArmPlanner` method plans it. ``skill_name`` is the ACSG's primitive name
(`agent.acsg.graph.PRIMITIVES`); the first docstring line is what ``homebot skills`` lists.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from agent.perception.geometry import DEFAULT_AMOUNT
from worlds.bus.link import WorldLink
from skills.base import ArmSkill, SkillResult, SkillTarget
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlan, SkillPlanError



def _part(target: SkillTarget, kind: str, skill: str) -> None:
    geometry = target.geometry
    if geometry is None:
        raise SkillPlanError(f"target: {skill} needs the {kind}'s geometry (SkillTarget.geometry)")
    if geometry.kind != kind:
        handle = "vertical" if geometry.kind == "door" else "horizontal"
        raise SkillPlanError(f"target: {target.label or 'the part'} is a {geometry.kind} (its handle is {handle}), "
                             f"not a {kind}: use {skill.replace(kind, geometry.kind)}")


def _amount(target: SkillTarget, skill: str) -> float:
    if target.amount is None:
        raise SkillPlanError(f"target: {skill} needs the amount the part stands open (SkillTarget.amount)")
    return float(target.amount)


class _OpenPart(ArmSkill):
    """With ``hold`` the skill ends with the hand still on the handle, the part held open (for a
    look while nothing can swing it on), for the same kind's close made with ``held``."""

    kind = ""

    def __init__(self, link: WorldLink, name: str | None = None, *, hold: bool = False, **options: Any) -> None:
        super().__init__(link, name, **options)
        self.hold = hold

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: tuple[float, float, float],
             target: SkillTarget) -> SkillPlan:
        _part(target, self.kind, self.skill_name)
        amount = DEFAULT_AMOUNT[self.kind] if target.amount is None else float(target.amount)
        assert target.geometry is not None
        return planner.plan_open(q, base_pose, target.geometry, amount, surface_z=target.surface_z,
                                 skill=self.skill_name, hold=self.hold)

    def summary(self, result: SkillResult) -> str:
        return f"{super().summary(result)}; opened {_amount_text(self.kind, result.achieved)}"


class _ClosePart(ArmSkill):
    """With ``held`` the hand already holds the handle (an open made with ``hold``): it pushes the
    part shut from there instead of grasping it first."""

    kind = ""

    def __init__(self, link: WorldLink, name: str | None = None, *, held: bool = False, **options: Any) -> None:
        super().__init__(link, name, **options)
        self.held = held

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: tuple[float, float, float],
             target: SkillTarget) -> SkillPlan:
        _part(target, self.kind, self.skill_name)
        assert target.geometry is not None
        amount = _amount(target, self.skill_name)
        if self.held:
            if target.geometry_is_open:
                raise SkillPlanError(f"target: {self.skill_name} of a held part needs its geometry as seen closed")
            return planner.plan_close_held(q, base_pose, target.geometry, amount, surface_z=target.surface_z,
                                           skill=self.skill_name)
        return planner.plan_close(q, base_pose, target.geometry, amount, geometry_is_open=target.geometry_is_open,
                                  surface_z=target.surface_z, skill=self.skill_name)

    def summary(self, result: SkillResult) -> str:
        return f"{super().summary(result)}; left open {_amount_text(self.kind, result.achieved)}"


def _amount_text(kind: str, value: float | None) -> str:
    if value is None:
        return "?"
    return f"{value:.3f} m" if kind == "drawer" else f"{math.degrees(value):.1f}°"


class OpenDoor(_OpenPart):
    """Open a door by its handle: grasp, swing it about the hinge perception estimated, let go."""

    skill_name = "open_door"
    kind = "door"


class CloseDoor(_ClosePart):
    """Close an open door: grasp its handle where it stands open, swing it shut about its hinge."""

    skill_name = "close_door"
    kind = "door"


class OpenDrawer(_OpenPart):
    """Open a drawer by its handle: grasp, pull it straight out along the front's normal, let go."""

    skill_name = "open_drawer"
    kind = "drawer"


class CloseDrawer(_ClosePart):
    """Close an open drawer: grasp its handle where it stands out, push it straight back in."""

    skill_name = "close_drawer"
    kind = "drawer"


class _Pick(ArmSkill):
    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: tuple[float, float, float],
             target: SkillTarget) -> SkillPlan:
        missing = [name for name in ("object_point", "object_extent", "place_point") if getattr(target, name) is None]
        if missing:
            raise SkillPlanError(f"target: {self.skill_name} needs {', '.join(missing)}")
        assert target.object_point is not None and target.object_extent is not None and target.place_point is not None
        return planner.plan_pick(q, base_pose, target.object_point, target.object_extent, target.place_point,
                                 surface_z=target.surface_z, skill=self.skill_name)

    def summary(self, result: SkillResult) -> str:
        place = result.info.get("place_point")
        where = "" if place is None else f" at ({place[0]:.2f}, {place[1]:.2f})"
        return f"{super().summary(result)}; put down{where}"


class PickAway(_Pick):
    """Pick an object from the top and put it down at an idle spot, out of the way of what it hid."""

    skill_name = "pick_away"


class PickBack(_Pick):
    """Pick an object back up from its idle spot and put it down where it stood before."""

    skill_name = "pick_back"


class LookAt(ArmSkill):
    """Move the wrist camera to look at a point from a short standoff (into a drawer, past a door)."""

    skill_name = "move_camera"

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: tuple[float, float, float],
             target: SkillTarget) -> SkillPlan:
        if target.look_point is None:
            raise SkillPlanError("target: move_camera needs look_point")
        return planner.plan_look(q, base_pose, target.look_point, standoff_m=target.standoff_m,
                                 pitch_deg=target.pitch_deg, surface_z=target.surface_z, skill=self.skill_name)


#: Every primitive by its ACSG name.
PRIMITIVES: dict[str, type[ArmSkill]] = {
    skill.skill_name: skill for skill in (OpenDoor, CloseDoor, OpenDrawer, CloseDrawer, PickAway, PickBack, LookAt)
}
