"""Motion plans for the arm primitives: from where the arm is to the steps the world will run.

Pure planning (Pinocchio IK from `skills.arm.kinematics`, Ruckig trajectories from
`skills.arm.trajectory`), no py_trees and no bus: given the arm's joint positions, the base's
pose and a target perceived in the world frame, each ``plan_*`` method of `ArmPlanner` returns a
`skills.arm.skill_plan.SkillPlan`.

Frames. Targets come in the world frame (z up); the kinematics work in the robot's root frame (the
URDF's ``base_link``: the floor under the base's axis, x ahead), so every pose is taken into it
with the base pose (x, y, yaw). The base pose itself is read off an arm state: the TCP's world pose
times the inverse of its forward kinematics (`ArmPlanner.base_pose_from`).

The primitives (RoboEXP's seven, §2 of the spec), each family in its own module:

- open / close a door or drawer, and push shut one held open (`skills.arm.part_plans`);
- pick an object away / back (`skills.arm.pick_plans`);
- move the wrist camera (`skills.arm.view_plans`);
- move the joints, stow the arm (`skills.arm.fold_plans`).

Every plan accumulates its steps in a `skills.arm.plan_builder.PlanBuilder` and solves its IK with
a `skills.arm.ik_search.IKSearch` seeded afresh, so planning is deterministic. Free moves are
joint-space; with a ``surface_z`` the hand is kept above it over the whole move
(`skills.arm.plan_builder.PlanBuilder.free_move`: else with the lift raised on the way, else a
planning error). Beyond that nothing here checks collisions: the world reports contacts, and free
moves and approaches stop on the first one.

Failures raise `skills.arm.skill_plan.SkillPlanError` naming the stage and the target: ``IK: grasp
pose of drawer handle unreachable: ...``, ``clearance: the hand at the drawer handle (0.822 m
high) would come ...``.
"""

from __future__ import annotations

from skills.arm import fold_plans, part_plans, pick_plans, view_plans
from skills.arm.arm_model import ArmModel


class ArmPlanner(ArmModel):
    """Plans the primitives for one robot: its URDF, its lift-and-arm joints and their limits.

    The ``plan_*`` methods are the primitive families' planners with this arm bound as their first
    argument (see each for its arguments): each takes where the arm is (``q``) and where the base
    stands (``base_pose``) and returns a plan from there, and none depends on an earlier call.

    Args:
        *args: as for `skills.arm.arm_model.ArmModel` (usually built by ``ArmPlanner.from_description``).
        **kwargs: likewise.
    """

    plan_open = part_plans.plan_open
    plan_close = part_plans.plan_close
    plan_close_held = part_plans.plan_close_held
    plan_pick = pick_plans.plan_pick
    plan_look = view_plans.plan_look
    plan_joint_move = fold_plans.plan_joint_move
    plan_stow = fold_plans.plan_stow
