"""Explore: choose the next frontier (plain FBE here), or say that nothing is left to explore."""

from __future__ import annotations

import contextlib

import py_trees
from py_trees.common import Access, Status

from agent import blackboard as bb
from agent.planning.explore import ExploreConfig, nearest_frontier, plan_move, reachable_frontiers
from agent.runtime.timing import StageTimer


class SelectFrontier(py_trees.behaviour.Behaviour):
    """Writes a `MovePlan` toward the nearest reachable frontier; FAILURE when there is none."""

    def __init__(self, config: ExploreConfig = ExploreConfig(), timer: StageTimer | None = None,
                 name: str = "SelectFrontier") -> None:
        super().__init__(name)
        self.config = config
        self.timer = timer
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.MAP, access=Access.READ)
        self.blackboard.register_key(bb.OBSERVATION, access=Access.READ)
        self.blackboard.register_key(bb.PLAN, access=Access.WRITE)

    def update(self) -> Status:
        world_map = self.blackboard.get(bb.MAP)
        robot_xy = self.blackboard.get(bb.OBSERVATION).base_pose[:2]
        with self.timer.measure("planning") if self.timer else contextlib.nullcontext():
            candidates = reachable_frontiers(world_map, robot_xy, self.config)
            index = nearest_frontier(candidates)
            plan = plan_move(candidates, index, robot_xy, self.config) if index is not None else None
        self.blackboard.set(bb.PLAN, plan)
        if plan is None:
            self.feedback_message = "no reachable frontier is left"
            return Status.FAILURE
        self.feedback_message = (
            f"{len(candidates.frontiers)} frontiers; nearest at {plan.goal_distance_m:.1f} m"
        )
        return Status.SUCCESS


class MarkExplorationComplete(py_trees.behaviour.Behaviour):
    """Records that the home has no reachable frontier left, so the episode can answer now."""

    def __init__(self, name: str = "NothingLeftToExplore") -> None:
        super().__init__(name)
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.EXPLORATION_COMPLETE, access=Access.WRITE)

    def update(self) -> Status:
        self.blackboard.set(bb.EXPLORATION_COMPLETE, True)
        self.feedback_message = "every reachable frontier has been explored"
        return Status.SUCCESS
