"""Plans for moving the wrist camera: one free move that puts the camera's optical frame at a
standoff from a point, its optical axis on the point (IK "axis" mode: the rotation about the axis
is free), trying steeper and shallower views and shorter and longer standoffs until one is
reachable; with ``keep_off`` (what stands near: `skills.arm.clearance.Clearance`), first until one
at which the whole arm and the hand keep clear of it, the free move there taking a route that does
(drawer-only 1011 of tuning-wide: the way to a look into a drawer just opened pushed it 8 cm back
in, and the hand closing it later found nothing where the handle was).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.clearance import Clearance
from skills.arm.frames import base_transform, pose_at
from skills.arm.ik_search import IKSearch
from skills.arm.plan_builder import PlanBuilder
from skills.arm.skill_plan import SkillPlan, SkillPlanError, best_failure, checked_vector

#: Wrist-camera views tried: (degrees below the horizontal, standoff m), best first.
LOOK_VIEWS = tuple((pitch, d) for d in (0.3, 0.4, 0.25, 0.5) for pitch in (60.0, 45.0, 75.0, 90.0, 30.0))


def plan_look(arm: ArmModel, q: np.ndarray, base_pose: Pose2D, point: Sequence[float], *,
              standoff_m: float | None = None, pitch_deg: float | None = None,
              surface_z: float | None = None, skill: str = "move_camera",
              keep_off: np.ndarray | None = None) -> SkillPlan:
    """Put the wrist camera at a standoff from a point, looking at it from above and in front.

    Args:
        arm: the arm planned for, with a wrist camera frame.
        q: where the arm is.
        base_pose: where the base stands.
        point: what to look at (world).
        standoff_m: the camera's distance from the point (default: each of `LOOK_VIEWS`' in turn).
        pitch_deg: the view's angle below the horizontal (default: likewise).
        surface_z: the table's top, which the free move keeps the hand above.
        skill: the plan's name.
        keep_off: (N, 3) points of what stands near, to keep the arm and hand off where a view lets them.

    Returns:
        The plan; ``info`` has the camera pose reached, the standoff, the pitch, and whether the
        view was checked clear.

    Raises:
        SkillPlanError: no camera frame, a bad point, or no view reachable.
    """
    if arm.camera is None:
        raise SkillPlanError("look: the planner has no wrist camera frame")
    target = checked_vector(point, "point")
    here = arm.start_configuration(q)
    ik = IKSearch(arm, here, base_pose)
    builder = PlanBuilder(arm, here, base_pose, surface_z)
    base = base_transform(base_pose)
    heading = target[:2] - base[:2, 3]
    if np.linalg.norm(heading) < 0.2:  # right over the base: look along its heading
        heading = base[:2, 0]
    heading = heading / np.linalg.norm(heading)
    views = [(p, d) for p, d in LOOK_VIEWS if (pitch_deg is None or p == pitch_deg)
             and (standoff_m is None or d == standoff_m)] or [(pitch_deg or 60.0, standoff_m or 0.3)]
    near = None if keep_off is None else np.asarray(keep_off, dtype=float).reshape(-1, 3)
    clearance = Clearance(arm, base, surface_z, near) if near is not None and len(near) else None
    failures, fallback = [], None
    for pitch, distance in views:
        a = math.radians(pitch)
        view = np.array([math.cos(a) * heading[0], math.cos(a) * heading[1], -math.sin(a)])
        x_axis = np.cross(view, [0.0, 0.0, 1.0]) if abs(view[2]) < 0.999 else np.array([1.0, 0.0, 0.0])
        x_axis /= np.linalg.norm(x_axis)
        camera = pose_at(np.column_stack([x_axis, np.cross(view, x_axis), view]), target - distance * view)
        try:
            goal = ik.ik(camera, f"wrist camera pose {distance:.2f} m from the point at {pitch:.0f}°",
                         mode="axis", kinematics=arm.camera)
        except SkillPlanError as error:
            failures.append(str(error))
            continue
        fallback = fallback or (goal, distance, pitch)
        if clearance is None or clearance.problem(goal, hand=True) is None:
            builder.clearance = clearance
            return _view(builder, arm, ik, goal, target, distance, pitch, skill, clear=clearance is not None)
    if fallback is not None:  # no view keeps clear: the first that reaches, its way unchecked
        goal, distance, pitch = fallback
        return _view(builder, arm, ik, goal, target, distance, pitch, skill, clear=False)
    raise SkillPlanError(best_failure(failures, "look"))


def _view(builder: PlanBuilder, arm: ArmModel, ik: IKSearch, goal: np.ndarray, target: np.ndarray, distance: float,
          pitch: float, skill: str, clear: bool) -> SkillPlan:
    """The plan of one view: the free move to ``goal``."""
    assert arm.camera is not None
    builder.free_move("to the view", goal)
    reached = builder.base @ arm.camera.forward(goal)
    info = {"camera_pose": reached, "point": target, "standoff_m": distance, "pitch_deg": pitch, "clear": clear}
    return builder.finish(skill, info, ik)
