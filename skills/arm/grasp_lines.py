"""The straight TCP lines onto and off a grasp: backing off along the gripper's axis and
withdrawing towards the base, going on past a grasp to find a top by touch, lifting fingertips
off a bar.
"""

from __future__ import annotations

import numpy as np

from skills.arm.frames import shifted
from skills.arm.grasps import LIFT_OFF_M, TOUCH_SEARCH_M, UP, local_pose
from skills.arm.ik_search import LINE_STEP_M, IKSearch
from skills.arm.skill_plan import SkillPlanError
from skills.arm.tcp_paths import line_poses

#: How far out along the gripper's axis a grasp is approached from and retreated to.
APPROACH_M = 0.10
#: A part skill ends with the hand drawn straight back towards the base until it is this far ahead
#: of the base's axis (at the height and on the side it let go), clear of what it opened.
WITHDRAW_AHEAD_M = 0.35


def backed_off(ik: IKSearch, q: np.ndarray, pose: np.ndarray, what: str) -> np.ndarray:
    """The way off a grasp (reversed, the way onto it), clear of what the hand held.

    Straight back along the gripper's axis by `APPROACH_M`, then, where that is still further out,
    straight back towards the base until the hand is `WITHDRAW_AHEAD_M` ahead of its axis (at the
    same height and on the same side). The second leg is left out when it is out of reach.

    Args:
        ik: the plan's IK.
        q: where the arm is, the TCP at ``pose``.
        pose: the TCP's 4×4 world pose.
        what: the line in words, for the error.

    Returns:
        (k, dof) joint waypoints, ``q`` first.

    Raises:
        SkillPlanError: the first leg is out of reach.
    """
    out = pose @ local_pose(z=-APPROACH_M)
    waypoints = ik.path(q, line_poses(pose, out, LINE_STEP_M), what)
    local = ik.to_base @ out
    if local[0, 3] > WITHDRAW_AHEAD_M + 0.02:
        target = local.copy()
        target[0, 3] = WITHDRAW_AHEAD_M
        try:
            back = ik.path(waypoints[-1], line_poses(out, ik.base @ target, LINE_STEP_M), f"withdrawal from {what}")
        except SkillPlanError:
            return waypoints
        waypoints = np.vstack([waypoints, back[1:]])
    return waypoints


def searched(ik: IKSearch, waypoints: np.ndarray, pose: np.ndarray, what: str, straight_down: bool = False
             ) -> np.ndarray:
    """A touch grasp's approach, which stops where the fingertips touch: the way to the grasp
    carried on `skills.arm.grasps.TOUCH_SEARCH_M` further, along the gripper's axis (onto a bar,
    into the front behind it) or ``straight_down`` (onto an object's top). Along its axis, a hand
    leaning back 65° went 0.8 cm lower, and the top of a box put down 1.4 cm lower than the memory
    had it was never touched (recursive 1025 of tuning-wide); a search far enough along the axis to
    come that low slid the fingertips 3 cm on across the top, and the box went back 3 cm off.

    Args:
        ik: the plan's IK.
        waypoints: the approach, ending with the TCP at ``pose``.
        pose: the grasp's TCP pose (world).
        what: the approach in words, for the error.
        straight_down: search straight down rather than along the gripper's axis.

    Returns:
        ``waypoints`` with the search beyond the grasp appended.

    Raises:
        SkillPlanError: the search is out of reach.
    """
    end = shifted(pose, -TOUCH_SEARCH_M * UP) if straight_down else pose @ local_pose(z=TOUCH_SEARCH_M)
    beyond = ik.path(waypoints[-1], line_poses(pose, end, LINE_STEP_M), what)
    return np.vstack([waypoints, beyond[1:]])


def lifted_off(ik: IKSearch, q: np.ndarray, pose: np.ndarray, what: str) -> np.ndarray:
    """`backed_off` from a touch grasp on a bar: the fingertips, resting on the bar and opened along
    it, first lift straight up off it by `skills.arm.grasps.LIFT_OFF_M`; backing off along the
    pitched gripper axis at once would drag the bar out with them.

    Args:
        ik: the plan's IK.
        q: where the arm is, the fingertips on the bar.
        pose: the TCP's 4×4 world pose there.
        what: the retreat in words, for the error.

    Returns:
        (k, dof) joint waypoints from ``q``: the lift, then the way back.

    Raises:
        SkillPlanError: the lift or the first leg back is out of reach.
    """
    up = shifted(pose, LIFT_OFF_M * UP)
    lift = ik.path(q, line_poses(pose, up, LINE_STEP_M), what)
    return np.vstack([lift, backed_off(ik, lift[-1], up, what)[1:]])
