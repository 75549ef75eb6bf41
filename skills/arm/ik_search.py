"""IK for planning: world targets solved from a few structured seeds, then random restarts drawn
from one seeded generator per plan, and Cartesian paths in the world frame; the time and the
number of solves are counted for the plan's report.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

import numpy as np

from agent.pose import Pose2D
from skills.arm.arm_model import ArmModel
from skills.arm.frames import base_transform
from skills.arm.ik_descent import IKMode
from skills.arm.ik_solver import plan_cartesian_path, solve_ik
from skills.arm.kinematics import ArmKinematics
from skills.arm.skill_plan import SkillPlanError
from skills.arm.tcp_paths import line_poses

#: IK seeds reaching ahead with the hand level: fingers above each other (a level bar) or side by side.
_AHEAD = ((0.2, 0.0, 0.0, 0.0, -2.0, 0.0, 3.57, -0.785), (0.2, 0.0, 0.0, 0.0, -2.0, 0.0, 3.57, 0.785))
#: Cartesian step of approaches, pulls and carries (m).
LINE_STEP_M = 0.01
#: Random restarts after the seeds when seeking postures for a clear chain (`IKSearch.clear_chain`),
#: which tries many targets in turn.
CLEAR_RESTARTS = 4
#: Postures of the first stage that pass the check followed through the chain at the most.
CLEAR_POSTURES = 3


class IKSearch:
    """The IK of one plan: world targets taken into the robot's frame, solved reproducibly.

    Args:
        arm: the arm planned for.
        here: where the arm is when planning starts (clipped into the limits): the last seed.
        base_pose: where the base stands.
    """

    def __init__(self, arm: ArmModel, here: np.ndarray, base_pose: Pose2D) -> None:
        self.arm = arm
        self.here = here
        self.base = base_transform(base_pose)
        self.to_base = np.linalg.inv(self.base)
        self.rng = np.random.default_rng(arm.seed)
        #: IK time (s) and solves so far, for the plan's report.
        self.seconds = 0.0
        self.solves = 0
        # Postures and Cartesian paths already solved in this plan: trying the ways in and out of a
        # grasp in turn (`clear_chain`) asks for the same ones many times.
        self._postures: dict[bytes, list[np.ndarray]] = {}
        self._paths: dict[bytes, np.ndarray | str] = {}

    def seeds(self, first: np.ndarray | None, target_local: np.ndarray) -> list[np.ndarray]:
        """IK seeds close to the target's posture, which keep IK off contorted solutions.

        Args:
            first: the previous waypoint of a chain, tried first; None for none.
            target_local: the target's 4×4 pose in the robot's frame.

        Returns:
            ``first`` if given, then the ready pose and postures reaching ahead, each turned
            (joint 1) towards the target and as they are, then where the arm is.
        """
        ready = self.arm.ready
        shoulder = ready.copy()
        toward = math.atan2(target_local[1, 3], target_local[0, 3] - 0.08)  # panda_link0 is 8 cm ahead
        postures = [ready, *(np.array(seed) for seed in _AHEAD)]
        turned = []
        for posture in postures:
            seed = posture.copy()
            seed[1] = shoulder[1] + toward
            turned.append(seed)
        seeds = [*turned, *postures, self.here]
        return [first, *seeds] if first is not None else seeds

    def ik(self, pose_world: np.ndarray, what: str, seed: np.ndarray | None = None, mode: IKMode = "pose",
           kinematics: ArmKinematics | None = None) -> np.ndarray:
        """One configuration reaching a world pose: the first of `solutions`.

        Args:
            pose_world: the frame's 4×4 target (world).
            what: the target in words, for the error.
            seed: tried before the other seeds.
            mode: what must match.
            kinematics: the frame's kinematics (default: the TCP's).

        Returns:
            The joint positions.

        Raises:
            SkillPlanError: no seed and no restart reaches it.
        """
        for q in self.solutions(pose_world, what, seed, mode, kinematics):
            return q
        raise AssertionError("solutions() raises when it finds none")

    def solutions(self, pose_world: np.ndarray, what: str, seed: np.ndarray | None = None, mode: IKMode = "pose",
                  kinematics: ArmKinematics | None = None, restarts: int = 10) -> Iterator[np.ndarray]:
        """Distinct configurations reaching a world pose, so that a chain can try the arm's postures in turn.

        Args:
            pose_world: the frame's 4×4 target (world).
            what: the target in words, for the error.
            seed: tried before the other seeds (`seeds`).
            mode: what must match.
            kinematics: the frame's kinematics (default: the TCP's).
            restarts: random configurations tried after the seeds, drawn from the plan's generator.

        Yields:
            One configuration per seed or restart that converges to a posture not found yet.

        Raises:
            SkillPlanError: naming ``what``, when there is none at all.
        """
        kin = kinematics or self.arm.kin
        target = self.to_base @ pose_world
        found: list[np.ndarray] = []
        reason = ""
        starts = [*self.seeds(seed, target), *(kin.random_configuration(self.rng) for _ in range(restarts))]
        for start in starts:
            began = time.perf_counter()
            result = solve_ik(kin, target, kin.clip(start), self.rng, mode=mode, max_restarts=0)
            self.seconds += time.perf_counter() - began
            self.solves += 1
            if not result.success:
                reason = reason or result.reason
                continue
            if all(np.abs(result.q - other).max() > 0.3 for other in found):
                found.append(result.q)
                yield result.q
        if not found:
            raise SkillPlanError(f"IK: {what} unreachable: {reason}")

    def path(self, start_q: np.ndarray, poses_world: Sequence[np.ndarray], what: str) -> np.ndarray:
        """Joint waypoints taking the TCP through world poses in turn.

        Args:
            start_q: where the path starts.
            poses_world: the TCP's 4×4 poses (world), close together.
            what: the path in words, for the error.

        Returns:
            (k, dof) waypoints, ``start_q`` first.

        Raises:
            SkillPlanError: a pose is unreachable or needs a jump.
        """
        key = np.asarray(start_q, dtype=float).tobytes() + np.asarray(poses_world, dtype=float).tobytes()
        if key not in self._paths:
            began = time.perf_counter()
            result = plan_cartesian_path(self.arm.kin, start_q, [self.to_base @ pose for pose in poses_world],
                                         max_joint_jump=0.35, max_deviation=0.004)
            self.seconds += time.perf_counter() - began
            self.solves += len(poses_world)
            self._paths[key] = result.q if result.success else result.reason
        found = self._paths[key]
        if isinstance(found, str):
            raise SkillPlanError(f"IK: {what} unreachable: {found}")
        return found

    def chain(self, stages: list[tuple[str, str, Any]]) -> list[np.ndarray]:
        """Joint waypoints for stages run one after the other from where the arm is.

        Args:
            stages: (what, kind, target) each: kind "free" an IK solution for the pose ``target``
                (a one-row array), "line" a straight TCP line from the previous stage's pose to
                ``target``, "path" the TCP through the poses ``target``.

        Returns:
            Each stage's waypoints, in order.

        Raises:
            SkillPlanError: naming the first stage that cannot be reached.
        """
        return self._chain_from(self.here, None, stages, None)

    def clear_chain(self, stages: list[tuple[str, str, Any]], check: PostureCheck) -> list[np.ndarray] | None:
        """The stages' waypoints (as `chain`, which must begin with a "free" stage) through postures
        that pass ``check``: the postures of the first stage are tried in turn (`solutions`) until
        one with which every waypoint of every stage passes; a later "free" stage takes the first
        of its postures that passes. The free move to the first stage is the plan's to route
        (`skills.arm.plan_builder.PlanBuilder.free_move`).

        Args:
            stages: as for `chain`.
            check: called with a stage's ``what`` and a joint vector, it returns a problem in words
                or None.

        Returns:
            Each stage's waypoints, or None when no posture passes (or none reaches).
        """
        what, kind, target = stages[0]
        assert kind == "free", "a clear chain begins with a free stage"
        key = np.asarray(target, dtype=float).tobytes()
        if key not in self._postures:
            try:
                self._postures[key] = list(self.solutions(target, what, restarts=CLEAR_RESTARTS))
            except SkillPlanError:
                self._postures[key] = []
        tried = 0
        try:
            for q in self._postures[key]:
                if tried == CLEAR_POSTURES:
                    break
                if check(what, q) is not None:
                    continue
                tried += 1
                chains = [q[None, :], *self._chain_from(q, target, stages[1:], check)]
                if not _failed(chains):
                    return chains
        except SkillPlanError:
            pass
        return None

    def _chain_from(self, q: np.ndarray, pose: np.ndarray | None, stages: list[tuple[str, str, Any]],
                    check: PostureCheck | None) -> list[np.ndarray]:
        """The stages' waypoints from ``q`` (the TCP at ``pose``); with ``check``, a stage that cannot
        be reached, or whose waypoints fail the check, ends the list early with an empty array
        rather than raising."""
        kin = self.arm.kin
        chains: list[np.ndarray] = []
        for what, kind, target in stages:
            try:
                if kind == "free":
                    q = self._free(target, what, None if pose is None else q, check)
                    chains.append(q[None, :])
                    pose = target
                elif kind == "line":
                    assert pose is not None
                    current = self.base @ kin.forward(q)
                    chains.append(self.path(q, line_poses(current, target, LINE_STEP_M), what))
                    q, pose = chains[-1][-1], target
                else:
                    chains.append(self.path(q, list(target), what))
                    q, pose = chains[-1][-1], target[-1]
            except SkillPlanError:
                if check is None:
                    raise
                chains.append(np.zeros((0, len(q))))
                return chains
            if check is not None and _first_problem(check, what, chains[-1][::2]) is not None:
                chains[-1] = np.zeros((0, len(q)))
                return chains
        return chains

    def _free(self, target: np.ndarray, what: str, seed: np.ndarray | None, check: PostureCheck | None) -> np.ndarray:
        """The first posture reaching ``target`` that passes ``check`` (the first at all without one,
        or when none does)."""
        if check is None:
            return self.ik(target, what, seed=seed)
        first = None
        for q in self.solutions(target, what, seed):
            first = q if first is None else first
            if check(what, q) is None:
                return q
        assert first is not None
        return first


#: What a chain's postures must pass: (stage, joint positions) -> a problem in words, or None.
PostureCheck = Callable[[str, np.ndarray], "str | None"]


def _failed(chains: list[np.ndarray]) -> bool:
    return any(len(chain) == 0 for chain in chains)


def _first_problem(check: PostureCheck, what: str, waypoints: np.ndarray) -> str | None:
    for q in waypoints:
        problem = check(what, q)
        if problem is not None:
            return f"{what}: {problem}"
    return None
