"""What a motion plan is: its steps (joint trajectories and gripper actions), the part a move
carries, and the error raised when there is no plan.

A `SkillPlan` is what the arm's planners (`skills.arm.planner.ArmPlanner`) hand to an executor: a
list of `Step`, each a ``move`` (joint samples (N, dof) every ``dt`` seconds for the world's
``arm_trajectory`` command, with the joint waypoints they pass through so the rest of a motion can
be re-timed from wherever the arm really stopped, and what to check when it ends) or a ``gripper``
action (``open`` or ``close``, and for a close what must then be held).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from agent.perception.part_geometry import PartGeometry
from agent.pose import Pose2D

#: Speeds as fractions of the joints' velocity limits: free moves, and moves near or holding things.
FREE_SPEED, CAREFUL_SPEED = 0.5, 0.25


class SkillPlanError(RuntimeError):
    """No plan: the text names the stage and the target, e.g. ``IK: grasp pose of drawer handle
    unreachable: target 1.02 m from the shoulder, beyond the arm's 0.95 m reach``.

    Args:
        *args: the message, as for any exception.
    """


def best_failure(failures: list[str], what: str) -> str:
    """The one failure worth reporting when every grasp variant or view failed.

    Args:
        failures: each variant's `SkillPlanError` text, in the order tried.
        what: what was planned, for when there was nothing to try.

    Returns:
        The failure of the variant that got furthest (stages are tried in order), and how many
        others failed.
    """
    if not failures:
        return f"{what}: no variant to try"
    stages = ("above", "wrist", "grasp", "down", "lift", "carry", "lower", "opening", "closing", "pre-grasp",
              "retreat", "back")

    def progress(message: str) -> int:
        return max((k for k, word in enumerate(stages) if f"IK: {word}" in message), default=-1)

    best = max(failures, key=progress)
    return f"{best} (and {len(failures) - 1} other grasp variants failed)" if len(failures) > 1 else best


def checked_vector(value: Sequence[float], name: str) -> np.ndarray:
    """A 3-vector argument of a plan (a point, a box's size), checked before any planning.

    Args:
        value: three numbers.
        name: the argument's name, for the error.

    Returns:
        The vector as a float array.

    Raises:
        SkillPlanError: not three finite numbers.
    """
    vector = np.asarray(value, dtype=float)
    if vector.shape != (3,) or not np.all(np.isfinite(vector)):
        raise SkillPlanError(f"{name}: expected 3 finite numbers, got {value!r}")
    return vector


@dataclass(frozen=True, eq=False)
class PartMotion:
    """What a move holding a handle should do to its part, so the executor can tell how far it got.

    Args:
        geometry: the part as seen closed.
        reference: the TCP's world position when it grasps the closed part.
        start: the part's opening when the move starts (m for drawers, rad for doors, 0 = closed).
        end: its opening when the move ends.
    """

    geometry: PartGeometry
    reference: np.ndarray
    start: float
    end: float

    def opening(self, tcp_point: np.ndarray) -> float:
        """The part's opening implied by where the TCP (which holds the handle) stands.

        Args:
            tcp_point: the TCP's world position.

        Returns:
            The opening, m along a drawer's normal or rad about a door's hinge.
        """
        g = self.geometry
        point = np.asarray(tcp_point, dtype=float)
        if g.kind == "drawer":
            return float((point - self.reference) @ g.normal)
        assert g.hinge_point is not None and g.hinge_axis is not None
        axis = g.hinge_axis
        a = self.reference - g.hinge_point
        b = point - g.hinge_point
        a, b = a - (a @ axis) * axis, b - (b @ axis) * axis
        return float(math.atan2(np.cross(a, b) @ axis, a @ b))

    @property
    def unit(self) -> str:
        """The opening's unit: "m" for drawers, "rad" for doors."""
        return "m" if self.geometry.kind == "drawer" else "rad"


@dataclass(frozen=True, eq=False)
class Step:
    """One command of a plan.

    Args:
        kind: "move" or "gripper".
        name: what the step does, in words.
        samples: a move's (N, dof) joint samples.
        dt: their period (s).
        waypoints: the joint waypoints the samples pass through (the first is where the move starts).
        speed: a fraction of the velocity limits the move was timed at.
        stop_on_contact: the move stops on the first contact the world reports.
        tcp_target: where the move ends the TCP (world).
        part_motion: what the move does to a held part.
        action: a gripper step's "open" or "close".
        expect_held: closing, what must then be held ("handle" or "object"; None: the fingers close
            on nothing, to touch with their tips).
        touch: "handle" or "object" when the move is a touch grasp's approach, which arrives when
            it stops on touching that; "support" when it lowers what the hand carries, which
            arrives where that is held back by what it is put on (the arm touching nothing);
            "clear" when it backs off what the hand let go of, which arrives where a touch too
            light to report holds it back.
        stop_on_new_contact: the move stops on the first contact it did not begin with (a carry
            back from the thing it met on its way).
    """

    kind: str
    name: str
    samples: np.ndarray | None = None
    dt: float = 0.0
    waypoints: np.ndarray | None = None
    speed: float = FREE_SPEED
    stop_on_contact: bool = False
    tcp_target: np.ndarray | None = None
    part_motion: PartMotion | None = None
    action: str | None = None
    expect_held: str | None = None
    touch: str | None = None
    stop_on_new_contact: bool = False

    @property
    def duration_s(self) -> float:
        """How long the move's samples last (0 for a gripper action)."""
        return 0.0 if self.samples is None else len(self.samples) * self.dt

    def describe(self) -> str:
        """The step in one line, for logs.

        Returns:
            The name and the gripper action, or the move's sample count and duration.
        """
        if self.kind == "gripper":
            return f"{self.name}: gripper {self.action}"
        assert self.samples is not None
        return f"{self.name}: {len(self.samples)} samples, {self.duration_s:.2f} s"


@dataclass(frozen=True, eq=False)
class SkillPlan:
    """The steps of one primitive and what planning them cost.

    Args:
        skill: the primitive's name (``open_drawer``, ``pick_away``...).
        steps: the steps, in the order to run them.
        base_pose: where the base stands for the whole plan.
        start_q: the joint positions the plan starts from.
        final_q: those it ends at.
        ik_ms: IK time over every grasp variant tried.
        ik_solves: IK calls, likewise.
        trajectory_ms: Ruckig time.
        planning_ms: all of it.
        info: what the skill reports afterwards (the grasp pose, the camera pose, the place
            point...), world frame.
    """

    skill: str
    steps: tuple[Step, ...]
    base_pose: Pose2D
    start_q: np.ndarray
    final_q: np.ndarray
    ik_ms: float
    ik_solves: int
    trajectory_ms: float
    planning_ms: float
    info: dict[str, Any] = field(default_factory=dict)

    @property
    def duration_s(self) -> float:
        """The motions' total duration (gripper actions not counted)."""
        return sum(step.duration_s for step in self.steps)

    def describe(self) -> str:
        """The plan in a few lines, for logs.

        Returns:
            A summary line (grasp, steps, motion time, planning cost), then one line per step.
        """
        grasp = f" ({self.info['grasp']} grasp)" if "grasp" in self.info else ""
        lines = [f"{self.skill}{grasp}: {len(self.steps)} steps, {self.duration_s:.1f} s of motion, planned in "
                 f"{self.planning_ms:.0f} ms ({self.ik_solves} IK solves {self.ik_ms:.0f} ms, "
                 f"trajectories {self.trajectory_ms:.0f} ms)"]
        lines += [f"  {step.describe()}" for step in self.steps]
        return "\n".join(lines)
