"""Explore: choose the next frontier (FBE or semantic), or say that nothing is left to explore."""

from __future__ import annotations

import contextlib
from typing import TYPE_CHECKING

import numpy as np
import py_trees
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from behaviours.choices import FrontierChoice
from agent.mapping.occupancy import ExplorationMap
from agent.planning.frontier_plan import Candidates, ExploreConfig, plan_move, reachable_frontiers
from agent.planning.frontier_choice import choose_frontier, frontier_probabilities, kept_goal
from agent.planning.semantic import FrontierWeightConfig, frontier_log_weights
from agent.timing import StageTimer

if TYPE_CHECKING:
    from agent.lfe.estimator import LearnedEstimator


class SelectFrontier(py_trees.behaviour.Behaviour):
    """Writes a `MovePlan` toward a reachable frontier, or no plan when there is none.

    It succeeds either way: "no frontier" is an answer, not a failure, and `MarkExplorationComplete`
    acts on it. Keeping the two apart means a move that fails later is reported as that failure.

    FBE takes the nearest frontier; the semantic methods sample one in proportion to its weight
    from the semantic map (Explore until Confident, eq. 4), with the episode's seeded generator;
    under the default rule both weigh the path length and keep to the frontier chosen until it is
    reached or gone (`agent.planning.frontier_choice`, which keeps it in ``frontier_goal``); LFE plans over the shipped network's estimates with the steps left (`agent.lfe.eqa_frontier`),
    loading the network on the first choice so that other methods never import torch. The
    candidates, with their share of the weight and the one chosen, go to ``frontier_choices``.

    Args:
        config: the exploration method and its settings.
        weights: the frontier weights' temperatures.
        rng: the episode's generator (a fixed one when None).
        timer: times the choice, if given.
        name: the node's name.
    """

    def __init__(self, config: ExploreConfig = ExploreConfig(), weights: FrontierWeightConfig = FrontierWeightConfig(),
                 rng: np.random.Generator | None = None, timer: StageTimer | None = None,
                 name: str = "SelectFrontier") -> None:
        super().__init__(name)
        self.config = config
        self.weights = weights
        self.semantic = config.strategy.use_semantic
        self.learned = config.strategy.learned
        self.estimator: LearnedEstimator | None = None
        self.rng = rng if rng is not None else np.random.default_rng(0)
        self.timer = timer
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.MAP, access=Access.READ)
        if self.semantic:
            self.blackboard.register_key(bb.SEMANTIC_MAP, access=Access.READ)
        if self.learned:
            self.blackboard.register_key(bb.BUDGET, access=Access.READ)
            self.blackboard.register_key(bb.ANSWER_LOG, access=Access.READ)
        self.blackboard.register_key(bb.OBSERVATION, access=Access.READ)
        self.blackboard.register_key(bb.PLAN, access=Access.WRITE)
        self.blackboard.register_key(bb.FRONTIER_GOAL, access=Access.WRITE)
        self.blackboard.register_key(bb.MAP_FIELDS, access=Access.WRITE)  # computes the map's fields once a step
        self.blackboard.register_key(bb.FRONTIER_CHOICES, access=Access.WRITE)

    def update(self) -> Status:
        world_map = self.blackboard.get(bb.MAP)
        robot_xy = self.blackboard.get(bb.OBSERVATION).base_pose[:2]
        with self.timer.measure("planning") if self.timer else contextlib.nullcontext():
            candidates = reachable_frontiers(world_map, robot_xy, self.config, self.blackboard.get(bb.MAP_FIELDS))
            centres = world_map.spec.to_world(np.array([f.centre for f in candidates.frontiers]).reshape(-1, 2))
            earlier_goal = self.blackboard.get(bb.FRONTIER_GOAL)
            log_weights = None
            if self.learned:
                index = self._learned_choice(world_map, robot_xy, candidates) if candidates.frontiers else None
            else:
                log_weights = self._log_weights(candidates)
                index = choose_frontier(centres, candidates.distances_m, log_weights, earlier_goal,
                                        self.config.choice, self.rng) if candidates.frontiers else None
            plan = plan_move(candidates, index, robot_xy, self.config) if index is not None else None
        goal = None if plan is None else world_map.spec.to_world(np.asarray(plan.frontier.centre))
        self.blackboard.set(bb.PLAN, plan)
        self.blackboard.set(bb.FRONTIER_GOAL, goal)
        self.blackboard.set(bb.FRONTIER_CHOICES, _choices(centres, candidates.distances_m, log_weights,
                                                          index if plan is not None else None))
        if plan is None:
            self.feedback_message = "no reachable frontier is left"
            return Status.SUCCESS
        kept = index == kept_goal(centres, earlier_goal, self.config.choice.keep_within_m)
        rule = ("Bellman over learned R_A, D" if self.learned else "kept the goal" if kept
                else "sampled by semantic weight" if self.semantic else "nearest")
        self.feedback_message = f"{len(candidates.frontiers)} frontiers; {rule} at {plan.goal_distance_m:.1f} m"
        return Status.SUCCESS

    def _log_weights(self, candidates: Candidates) -> np.ndarray | None:
        """The semantic methods' log w_p of the candidates; None for FBE, or when there are none."""
        if not (self.semantic and candidates.frontiers):
            return None
        return frontier_log_weights(candidates.frontiers, self.blackboard.get(bb.SEMANTIC_MAP), self.weights)

    def _learned_choice(self, world_map: ExplorationMap, robot_xy: tuple[float, float], candidates: Candidates) -> int:
        from agent.lfe.estimator import LearnedEstimator
        from agent.lfe.eqa_frontier import lfe_frontier

        if self.estimator is None:
            self.estimator = LearnedEstimator.load()
        steps_left = self.blackboard.get(bb.BUDGET) - len(self.blackboard.get(bb.ANSWER_LOG))
        return lfe_frontier(world_map, robot_xy, candidates, self.estimator, steps_left, self.config.max_step_m).choice


def _choices(centres: np.ndarray, distances_m: np.ndarray, log_weights: np.ndarray | None,
             chosen: int | None) -> list[FrontierChoice]:
    """The candidates as ``frontier_choices`` keeps them: centre, path length, share of the weight."""
    shares = frontier_probabilities(log_weights) if log_weights is not None else [None] * len(centres)
    return [FrontierChoice(round(float(x), 3), round(float(y), 3), round(float(distance), 3),
                           None if share is None else float(share), i == chosen)
            for i, ((x, y), distance, share) in enumerate(zip(centres, distances_m, shares))]


class MarkExplorationComplete(py_trees.behaviour.Behaviour):
    """Records that the home has no reachable frontier left, so the episode can answer now.

    SUCCESS only when `SelectFrontier` found no frontier (no plan); FAILURE otherwise, so the
    move toward the planned frontier runs next.

    Args:
        name: the node's name.
    """

    def __init__(self, name: str = "MarkExplorationComplete") -> None:
        super().__init__(name)
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.PLAN, access=Access.READ)
        self.blackboard.register_key(bb.EXPLORATION_COMPLETE, access=Access.WRITE)

    def update(self) -> Status:
        if self.blackboard.get(bb.PLAN) is not None:
            self.feedback_message = "a frontier is planned"
            return Status.FAILURE
        self.blackboard.set(bb.EXPLORATION_COMPLETE, True)
        self.feedback_message = "every reachable frontier has been explored"
        return Status.SUCCESS
