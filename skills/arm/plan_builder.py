"""Accumulating a plan's steps: moves timed with Ruckig from wherever the previous step left the
arm, gripper actions, and free joint-space moves that keep the hand above a surface.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.clearance import Clearance
from skills.arm.free_path import connect, shortcut
from skills.arm.frames import base_transform
from skills.arm.grasps import HandleGrasp, ObjectGrasp, hand_bottom
from skills.arm.ik_search import IKSearch
from skills.arm.skill_plan import PartMotion, SkillPlan, SkillPlanError, Step

#: How far above ``surface_z`` the hand keeps.
SURFACE_CLEARANCE_M = 0.01
#: How far a free move tries raising the lift to swing the arm over a surface, least first (m).
LIFT_RISES_M = (0.15, 0.3, 0.45)
#: An arm within this (rad or m, any joint) of its stowed or ready pose folds without backing off first.
FOLDED_RAD = 0.1
#: How far (rad or m, any joint) a way round may go from where the arm starts before it must keep
#: clear: an arm that just let go of a door stands touching it.
ESCAPE_RAD = 0.15


class PlanBuilder:
    """The steps of one plan, from a start configuration; each move starts where the plan has the arm.

    Args:
        arm: the arm planned for.
        start: where the arm starts (`ArmModel.start_configuration`).
        base_pose: where the base stands.
        surface_z: the top of the surface the hand works over (world z), which free moves keep
            the hand above; None for none.
        clearance: what the whole arm keeps clear of (`skills.arm.clearance.Clearance`): free
            moves take the first of their routes that does; None for no such check.
    """

    def __init__(self, arm: ArmModel, start: np.ndarray, base_pose: Pose2D, surface_z: float | None = None,
                 clearance: Clearance | None = None) -> None:
        self.arm = arm
        self.surface_z = surface_z
        self.clearance = clearance
        self.start = start
        #: Where the plan has the arm: the end of the last move.
        self.q = start.copy()
        self.base_pose = Pose2D.of(base_pose)
        self.base = base_transform(self.base_pose)
        self.steps: list[Step] = []
        self.began = time.perf_counter()
        self.trajectory_s = 0.0

    def step(self, name: str, waypoints: np.ndarray, careful: bool, stop_on_contact: bool = False,
             tcp_target: np.ndarray | None = None, part_motion: PartMotion | None = None,
             touch: str | None = None, pass_through: bool = True) -> Step:
        """A move from where the plan has the arm, not yet added to the plan.

        Args:
            name: what the move does.
            waypoints: (n, dof) joint waypoints; where the plan has the arm is put first if missing.
            careful: at the careful speed (near or holding things), else the free speed.
            stop_on_contact: the move stops on the first contact.
            tcp_target: where it ends the TCP (world).
            part_motion: what it does to a held part.
            touch: what the move arrives on when it is held back (`Step.touch`).
            pass_through: pass the waypoints at speed; False: stop at each (`ArmModel.samples`).

        Returns:
            The timed move.

        Raises:
            SkillPlanError: Ruckig finds no trajectory.
        """
        arm = self.arm
        speed = arm.careful_speed if careful else arm.free_speed
        waypoints = np.asarray(waypoints, dtype=float)
        if len(waypoints) and np.abs(waypoints[0] - self.q).max() > 1e-9:
            waypoints = np.vstack([self.q[None, :], waypoints])
        waypoints = arm.kin.clip(waypoints)
        began = time.perf_counter()
        try:
            samples = arm.samples(waypoints, speed, pass_through)
        except (RuntimeError, ValueError) as error:
            raise SkillPlanError(f"trajectory: {name}: {error}") from None
        self.trajectory_s += time.perf_counter() - began
        return Step("move", name, samples, arm.dt, waypoints, speed, stop_on_contact, tcp_target, part_motion,
                    touch=touch)

    def move(self, name: str, waypoints: np.ndarray, careful: bool, stop_on_contact: bool = False,
             tcp_target: np.ndarray | None = None, part_motion: PartMotion | None = None,
             touch: str | None = None) -> None:
        """Add a move; the plan then has the arm at its last waypoint.

        Args:
            name: what the move does.
            waypoints: (n, dof) joint waypoints (see `step`).
            careful: at the careful speed, else the free speed.
            stop_on_contact: the move stops on the first contact.
            tcp_target: where it ends the TCP (world).
            part_motion: what it does to a held part.
            touch: what the move arrives on when it is held back (`Step.touch`).

        Raises:
            SkillPlanError: Ruckig finds no trajectory.
        """
        self.steps.append(self.step(name, waypoints, careful, stop_on_contact, tcp_target, part_motion, touch))
        self.q = self.steps[-1].waypoints[-1].copy()

    def free_move(self, name: str, goal: np.ndarray, via_ready: bool = True, clearance: Clearance | None = None
                  ) -> None:
        """Add a joint-space move to ``goal`` that stops on contact.

        It goes by way of the ready pose when the arm starts or ends stowed (the way out of the
        base and back into it that every skill takes, so folding away from a view into a drawer
        retraces the way there instead of sweeping through the drawer). With a known surface the
        hand must stay `SURFACE_CLEARANCE_M` above it all the way; a straight joint-space move that
        dips lower is replaced by one with the lift raised on the way (the arm swings over, then the
        lift lets it down): by `LIFT_RISES_M` in turn, as little as clears the surface (the lift is
        the slowest joint).

        Args:
            name: what the move does.
            goal: the joint positions to end at.
            via_ready: go by way of the ready pose into and out of the stowed pose.
            clearance: what this move keeps clear of, where that is not the plan's own
                (``clearance``): the move away from a thing just put down keeps off it too.

        Raises:
            SkillPlanError: even the top of the lift's travel dips too low, or no trajectory.
        """
        arm = self.arm
        checks = self.clearance if clearance is None else clearance
        goal = np.asarray(goal, dtype=float)
        start = [self.q]
        stowed = arm.stowed is not None and np.abs(self.q - arm.stowed).max() < FOLDED_RAD
        if via_ready and stowed:
            start.append(arm.ready)
        end = [goal]
        into_stow = via_ready and arm.stowed is not None and np.abs(goal - arm.stowed).max() < FOLDED_RAD and not stowed
        if into_stow:
            end.insert(0, arm.ready)
        routes = [*self._over_the_surface(start, end)]
        if checks is not None and not any(np.abs(q - arm.ready).max() < FOLDED_RAD for q in (*start, *end)):
            routes += self._over_the_surface([*start, arm.ready], end)  # folded in on the way
        target = self.base @ arm.kin.forward(goal)
        low = math.inf
        above: Step | None = None  # the first route that keeps the hand above the surface
        clear = False
        # a goal posture that itself touches (the arm at an open door's handle lies along its leaf)
        arrival = end[0] if checks is not None and checks.problem(end[0], hand=True) else None
        for waypoints in routes:
            step = self.step(name, waypoints, careful=False, stop_on_contact=True, tcp_target=target)
            low = self.lowest(step)
            if self.surface_z is not None and low < self.surface_z + SURFACE_CLEARANCE_M:
                continue
            above = above or step
            if checks is None or checks.path_problem(
                    self._checked(step, via_ready and stowed, into_stow, arrival), every=3, hand=True) is None:
                above, clear = step, True
                break
        if not clear and checks is not None:
            above = self._way_round(name, start, end, target, checks, arrival is not None) or above
        if above is None:
            assert self.surface_z is not None
            raise SkillPlanError(f"free move: {name}: the hand would come down to {low:.3f} m, "
                                 f"{self.surface_z + SURFACE_CLEARANCE_M - low:.3f} m too low over the surface "
                                 f"at {self.surface_z:.3f} m, even with the lift up")
        self.steps.append(above)
        self.q = goal.copy()

    def _checked(self, step: Step, out_of_stow: bool, into_stow: bool, arrival: np.ndarray | None) -> np.ndarray:
        """The samples of a free move that are checked clear: those between the ready pose and the
        goal, and with an ``arrival`` that touches something itself, not those within `ESCAPE_RAD`
        of it (the chain it leads to is checked on its own). The legs between the stowed and the
        ready pose are every skill's way out of the base and back into it, and there the folded arm
        grazes the margin kept over the surface at the body's edge by a few millimetres: checked,
        every free move out of the stowed pose would be judged not clear, and go unchecked."""
        samples = step.samples
        if out_of_stow or into_stow:
            at_ready = int(np.argmin(np.abs(samples - self.arm.ready).max(axis=1)))  # passed once: not both
            samples = samples[at_ready:] if out_of_stow else samples[:at_ready + 1]
        if arrival is not None:
            samples = samples[np.abs(samples - arrival).max(axis=1) >= ESCAPE_RAD]
        return samples

    def _way_round(self, name: str, start: list[np.ndarray], end: list[np.ndarray], target: np.ndarray,
                   clearance: Clearance, arriving_touched: bool = False) -> Step | None:
        """A free move round what stands near (`skills.arm.free_path`), for when no straight route is
        clear: the whole arm clear of it, the hand above the surface. Where the arm starts touching
        something (the door it let go of), the first `ESCAPE_RAD` of the way out are not held
        against it; with ``arriving_touched`` (the way's end touches something), nor the last
        `ESCAPE_RAD` of the way in. The arm passes the way's waypoints at speed, or where that
        strays into something off the lines between them, stops at each (recursive 1108 of
        tuning-wide: the way round to an open door's handle was found, the trajectory passing its
        waypoints cut through the leaf, and the move taken unchecked swept a finger into it). None
        when no way is found, or even the trajectory stopping at each waypoint strays."""
        origin = start[-1]

        def valid(q: np.ndarray) -> bool:
            if float(np.abs(q - origin).max()) < ESCAPE_RAD:
                return True
            if self.surface_z is not None and hand_bottom(self.base @ self.arm.kin.forward(q), self.base,
                                                          self.arm.body_radius) < self.surface_z + SURFACE_CLEARANCE_M:
                return False
            if arriving_touched and float(np.abs(q - end[0]).max()) < ESCAPE_RAD:
                return True
            return clearance.problem(q, hand=True) is None

        rng = np.random.default_rng(self.arm.seed)
        way = connect(origin, end[0], valid, self.arm.kin.lower, self.arm.kin.upper, rng)
        if way is None:
            return None
        way = shortcut(way, valid, rng)
        for pass_through in (True, False):
            step = self.step(name, np.array([*start[:-1], *way, *end[1:]]), careful=False, stop_on_contact=True,
                             tcp_target=target, pass_through=pass_through)
            if all(valid(q) for q in self._checked(step, len(start) > 1, len(end) > 1, None)[::3]):
                return step
        return None

    def _over_the_surface(self, start: list[np.ndarray], end: list[np.ndarray]) -> list[np.ndarray]:
        """Joint routes from ``start`` to ``end``: straight, then with the lift raised on the way by
        `LIFT_RISES_M` in turn and to the top (over a known surface)."""
        arm = self.arm
        routes = [np.array([*start, *end])]
        lift = arm.lift_index
        if self.surface_z is not None and lift is not None:
            top = arm.kin.upper[lift]
            low_lift = max(start[-1][lift], end[0][lift])
            for rise in (*(r for r in LIFT_RISES_M if low_lift + r < top), math.inf):
                over = [start[-1].copy(), end[0].copy()]
                for q in over:
                    q[lift] = min(top, low_lift + rise)
                routes.append(np.array([*start, *over, *end]))
        return routes

    def lowest(self, step: Step) -> float:
        """How low the hand comes over a move, to keep it above a surface.

        Args:
            step: a move.

        Returns:
            The lowest world z of the hand (`skills.arm.grasps.hand_bottom`) over every third
            sample and the last, away from the base's body.
        """
        assert step.samples is not None
        kin = self.arm.kin
        picks = np.unique(np.r_[np.arange(0, len(step.samples), 3), len(step.samples) - 1])
        return min(hand_bottom(self.base @ kin.forward(step.samples[k]), self.base, self.arm.body_radius)
                   for k in picks)

    def gripper(self, action: str, name: str, expect_held: str | None = None) -> None:
        """Add a gripper action.

        Args:
            action: "open" or "close".
            name: what it does.
            expect_held: closing, what must then be held ("handle", "object"; None: nothing).
        """
        self.steps.append(Step("gripper", name, action=action, expect_held=expect_held))

    def grasp(self, way: HandleGrasp | ObjectGrasp, name: str, approach: np.ndarray, pose: np.ndarray, kind: str,
              what: str | None = None) -> None:
        """Add the approach to a grasp and the close on what it holds.

        The fingers close around the thing, or, for a touch grasp, close first and the approach
        ends where their tips touch it. A touch grasp's approach ends past the grasp
        (`skills.arm.grasp_lines.searched`), so the next move comes back to it; the executor
        re-times that move from wherever the touch stopped the arm.

        Args:
            way: the grasp.
            name: what the approach does.
            approach: its joint waypoints.
            pose: the grasp's TCP pose (world).
            kind: "handle" or "object".
            what: the thing held in words (default: ``kind``).
        """
        if way.touch:
            self.gripper("close", "close the fingers")
        self.move(name, approach, careful=True, stop_on_contact=True, tcp_target=pose,
                  touch=kind if way.touch else None)
        self.gripper("close", f"grasp the {what or kind}", expect_held=kind)

    def let_go(self, what: str, retreat: np.ndarray) -> None:
        """Add opening the hand on a thing and backing off it, as every part skill ends.

        Args:
            what: the thing in words.
            retreat: the back-off's joint waypoints.
        """
        self.gripper("open", f"let go of the {what}")
        self.move(f"back off the {what}", retreat, careful=True,
                  tcp_target=self.base @ self.arm.kin.forward(retreat[-1]), touch="clear")

    def finish(self, skill: str, info: dict[str, Any], ik: IKSearch | None = None) -> SkillPlan:
        """The plan made of the steps added.

        Args:
            skill: the primitive's name.
            info: what the skill reports afterwards.
            ik: the plan's IK, for its cost; None when the plan solved none.

        Returns:
            The plan, ending where the last move left the arm.
        """
        planning_ms = 1e3 * (time.perf_counter() - self.began)
        ik_s, solves = (0.0, 0) if ik is None else (ik.seconds, ik.solves)
        return SkillPlan(skill, tuple(self.steps), self.base_pose, self.start, self.q.copy(), 1e3 * ik_s,
                         solves, 1e3 * self.trajectory_s, planning_ms, info)
