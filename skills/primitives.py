"""The seven arm primitives of RoboEXP as behaviours: open and close doors and drawers, pick an
object away to an idle spot and back, and move the wrist camera to look at a point.

Each is a small `skills.base.ArmSkill`: the input ports it adds to the base's, and which
`skills.arm.planner.ArmPlanner` method plans it. ``skill_name`` is the name it is registered under
(pyproject.toml's ``homebot.skills`` entry points; `agent.acsg.primitives`), which the
scene-graph executor asks the registry for; the first docstring line is what ``homebot skills`` lists.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from agent.perception.part_geometry import PartGeometry
from agent.perception.part_motion import DEFAULT_AMOUNT
from agent.pose import Pose2D
from skills.base import ArmSkill, SkillResult
from skills.arm.grasps import ObjectGrasp
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlan, SkillPlanError
from skills.ports import input_port

_GEOMETRY = input_port("geometry", PartGeometry, "the door or drawer as perceived closed (its handle, hinge or "
                       "slide), unless geometry_is_open")
_PART_KEEP_OFF = input_port("keep_off", np.ndarray, "points (N, 3) of what stands near, neither the part nor the "
                           "piece it belongs to, which the arm is to keep off", default=None)
_PART_POINTS = input_port("part_points", np.ndarray, "points (N, 3) of the part and of its piece's handles where "
                          "they stand now, which the free move to the handle keeps off", default=None)


def _check_kind(geometry: PartGeometry, label: str, kind: str, skill: str) -> None:
    if geometry.kind != kind:
        handle = "vertical" if geometry.kind == "door" else "horizontal"
        raise SkillPlanError(f"target: {label or 'the part'} is a {geometry.kind} (its handle is {handle}), "
                             f"not a {kind}: use {skill.replace(kind, geometry.kind)}")


class _OpenPart(ArmSkill):
    """With ``hold`` the skill ends with the hand still on the handle, the part held open (for a
    look while nothing can swing it on), for the same kind's close bound with ``held``."""

    kind = ""
    ports = ArmSkill.ports + (
        _GEOMETRY,
        input_port("amount", float, "how far to open it (m or rad; default: the kind's usual opening)", default=None),
        input_port("hold", bool, "end with the hand still on the handle, the part held open", default=False),
        _PART_KEEP_OFF,
        _PART_POINTS,
    )

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: Pose2D,
             inputs: Mapping[str, Any]) -> SkillPlan:
        _check_kind(inputs["geometry"], inputs["label"], self.kind, self.skill_name)
        amount = DEFAULT_AMOUNT[self.kind] if inputs["amount"] is None else inputs["amount"]
        return planner.plan_open(q, base_pose, inputs["geometry"], amount, surface_z=inputs["surface_z"],
                                 skill=self.skill_name, hold=inputs["hold"], keep_off=inputs["keep_off"],
                                 part_points=inputs["part_points"])

    def summary(self, result: SkillResult) -> str:
        return f"{super().summary(result)}; opened {_amount_text(self.kind, result.achieved)}"


class _ClosePart(ArmSkill):
    """With ``held`` the hand already holds the handle (an open bound with ``hold``): it pushes the
    part shut from there instead of grasping it first, along the only path the handle allows
    (``keep_off`` and ``part_points`` have nothing to choose there)."""

    kind = ""
    ports = ArmSkill.ports + (
        _GEOMETRY,
        input_port("amount", float, "how far it stands open now (m or rad)"),
        input_port("geometry_is_open", bool, "the geometry was perceived with the part open by amount",
                   default=False),
        input_port("held", bool, "the hand already holds the handle (an open bound with hold)", default=False),
        _PART_KEEP_OFF,
        _PART_POINTS,
    )

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: Pose2D,
             inputs: Mapping[str, Any]) -> SkillPlan:
        geometry = inputs["geometry"]
        _check_kind(geometry, inputs["label"], self.kind, self.skill_name)
        if inputs["held"]:
            if inputs["geometry_is_open"]:
                raise SkillPlanError(f"target: {self.skill_name} of a held part needs its geometry as seen closed")
            return planner.plan_close_held(q, base_pose, geometry, inputs["amount"], surface_z=inputs["surface_z"],
                                           skill=self.skill_name)
        return planner.plan_close(q, base_pose, geometry, inputs["amount"],
                                  geometry_is_open=inputs["geometry_is_open"], surface_z=inputs["surface_z"],
                                  skill=self.skill_name, keep_off=inputs["keep_off"],
                                  part_points=inputs["part_points"])

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
    ports = ArmSkill.ports + (
        input_port("object_point", np.ndarray, "the object's top-down grasp point (x, y, z)"),
        input_port("object_extent", np.ndarray, "the extent of its points (dx, dy, dz)"),
        input_port("place_point", np.ndarray, "where the grasp point is to be once the object stands at its "
                   "destination (x, y, z); or (k, 3) such places, the first a clear way reaches taken"),
        input_port("keep_off", np.ndarray, "points (N, 3) of what stands near, neither the object nor what it "
                   "stands on, which the hand is to keep off", default=None),
        input_port("grasp_first", ObjectGrasp, "a grasp to try before all others: the one the object was "
                   "taken away by, to put it back the way it came", default=None),
        input_port("near_edge", bool, "after every other route, hold a top beyond the hand's reach from above "
                   "by its near edge", default=False),
    )

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: Pose2D,
             inputs: Mapping[str, Any]) -> SkillPlan:
        return planner.plan_pick(q, base_pose, inputs["object_point"], inputs["object_extent"], inputs["place_point"],
                                 surface_z=inputs["surface_z"], skill=self.skill_name, keep_off=inputs["keep_off"],
                                 grasp_first=inputs["grasp_first"], near_edge=inputs["near_edge"])

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
    ports = ArmSkill.ports + (
        input_port("look_point", np.ndarray, "the point to look at (x, y, z)"),
        input_port("standoff_m", float, "the camera's distance from it (default: the planner's)", default=None),
        input_port("pitch_deg", float, "the camera's pitch below level (default: the planner's)", default=None),
        input_port("keep_off", np.ndarray, "points (N, 3) of what stands near, which the arm is to keep off",
                   default=None),
    )

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: Pose2D,
             inputs: Mapping[str, Any]) -> SkillPlan:
        return planner.plan_look(q, base_pose, inputs["look_point"], standoff_m=inputs["standoff_m"],
                                 pitch_deg=inputs["pitch_deg"], surface_z=inputs["surface_z"], skill=self.skill_name,
                                 keep_off=inputs["keep_off"])
