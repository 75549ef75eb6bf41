"""Plans for folding the arm: a free joint-space move to given joint positions, and stowing the
arm into the base from wherever it is, a hand left out among things first backed straight out;
and whether the arm comes out of the base clear of what stands before a stand (`unfold_problem`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.clearance import Clearance
from skills.arm.frames import base_transform
from skills.arm.grasp_lines import backed_off
from skills.arm.ik_search import IKSearch
from skills.arm.plan_builder import FOLDED_RAD, PlanBuilder
from skills.arm.skill_plan import SkillPlan, SkillPlanError

#: How many postures of the way between the stowed and the ready pose `unfold_problem` checks.
UNFOLD_SAMPLES = 24


def plan_joint_move(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, goal: Sequence[float], *,
                    surface_z: float | None = None, skill: str = "move_joints") -> SkillPlan:
    """One free joint-space move of lift and arm (e.g. folding the arm away).

    Args:
        arm: the arm planned for.
        q: where the arm is.
        base_pose: where the base stands.
        goal: the joint positions to move to.
        surface_z: the table's top, which the move keeps the hand above.
        skill: the plan's name.

    Returns:
        The plan; ``info["goal"]`` is the goal.

    Raises:
        SkillPlanError: the goal is malformed or outside the joint limits, or the move dips onto the surface.
    """
    joints = np.asarray(goal, dtype=float)
    if joints.shape != (arm.kin.dof,) or not np.all(np.isfinite(joints)):
        raise SkillPlanError(f"goal: expected {arm.kin.dof} finite joint values, got {goal!r}")
    if not arm.kin.within_limits(joints):
        raise SkillPlanError(f"goal: {np.round(joints, 3).tolist()} lies outside the joint limits")
    builder = PlanBuilder(arm, arm.start_configuration(q), base_pose, surface_z)
    builder.free_move("to the goal", joints)
    return builder.finish(skill, {"goal": joints})


def plan_stow(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, *, surface_z: float | None = None,
              skill: str = "stow") -> SkillPlan:
    """Fold the arm into the base from wherever it is.

    A hand out among things (left at a handle or an object by a move that stopped short) first
    backs straight out along the gripper's axis and towards the base
    (`skills.arm.grasp_lines.backed_off`), as every skill ends: a fold begun at once would swing
    the hand through what it reaches into, and stop on touching it at its first sample. Where no
    straight way back can be planned, the arm folds from where it is. The fold stops on a contact
    it did not begin with (`Step.stop_on_new_contact`), so an arm left touching something folds
    away from it.

    Args:
        arm: the arm planned for, with a stowed pose.
        q: where the arm is.
        base_pose: where the base stands.
        surface_z: the table's top, which the moves keep the hand above.
        skill: the plan's name.

    Returns:
        The plan; ``info["goal"]`` is the stowed pose.

    Raises:
        SkillPlanError: the robot names no stowed pose, or the fold dips onto the surface.
    """
    if arm.stowed is None:
        raise SkillPlanError("stow: the robot description names no stowed pose")
    here = arm.start_configuration(q)
    ik = IKSearch(arm, here, base_pose)
    builder = PlanBuilder(arm, here, base_pose, surface_z)
    if min(np.abs(here - arm.stowed).max(), np.abs(here - arm.ready).max()) > FOLDED_RAD:
        pose = builder.base @ arm.kin.forward(here)
        try:
            back = backed_off(ik, here, pose, "the hand's way back")
        except SkillPlanError:
            back = None
        if back is not None:
            builder.move("back off", back, careful=True, tcp_target=builder.base @ arm.kin.forward(back[-1]))
    builder.free_move("to the stowed pose", arm.stowed)
    # leaving what the arm was left against (the door a back-off was held against): a move that
    # stops on any contact stops at its first sample there, and every drive after it is refused
    builder.steps[-1] = replace(builder.steps[-1], stop_on_contact=False, stop_on_new_contact=True)
    return builder.finish(skill, {"goal": arm.stowed}, ik)


def unfold_problem(arm: ArmModel, base_pose: Pose2D, near: np.ndarray) -> str | None:
    """What the arm would touch coming out of the base to the ready pose, with the base at
    ``base_pose``, or going back in: every skill's way out of the base and back into it
    (`PlanBuilder.free_move`), which no plan checks. Before a table's front the strip the arm
    works over is kept clear, but at its back the storage stands right before the base: an arm
    folded in there swept a finger into a drawer chest (recursive 1059 of tuning-wide).

    Args:
        arm: the arm, with a stowed pose.
        base_pose: where the base would stand.
        near: (N, 3) points of what stands near (world).

    Returns:
        What the links would touch on the way, in words (`Clearance.problem`); None for nothing,
        or where the robot names no stowed pose.
    """
    if arm.stowed is None:
        return None
    way = np.linspace(arm.stowed, arm.ready, UNFOLD_SAMPLES)
    return Clearance(arm, base_transform(base_pose), None, near).path_problem(way, hand=True)
