"""Stow: fold the arm back into the base. The example of a skill added to homebot (see the README).

A skill is a `skills.base.ArmSkill` subclass with a ``skill_name``, the input ports it adds to the
base's (none here: the base's ``surface_z`` is all it needs) and a ``plan`` method that turns the
arm's state and the inputs into a `SkillPlan`; the base class sends the plan's steps to the world,
stays RUNNING while the arm moves, checks the outcome and gives the `SkillResult` on its ``result``
port. One entry point in ``pyproject.toml`` registers it: ``homebot skills`` lists it and ``homebot
skill run stow`` runs it.
"""

from __future__ import annotations

from typing import Any, Mapping

import numpy as np

from skills.base import ArmSkill
from skills.arm.planner import ArmPlanner
from skills.arm.skill_plan import SkillPlan
from agent.pose import Pose2D


class Stow(ArmSkill):
    """Fold the arm back into the base (its stowed pose), e.g. before the robot drives on.

    A hand left out against something is first backed straight out (`ArmPlanner.plan_stow`)."""

    skill_name = "stow"

    def plan(self, planner: ArmPlanner, q: np.ndarray, base_pose: Pose2D,
             inputs: Mapping[str, Any]) -> SkillPlan:
        return planner.plan_stow(q, base_pose, surface_z=inputs["surface_z"], skill=self.skill_name)
