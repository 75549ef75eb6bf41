"""LFE as the EQA tree's exploration method: the Bellman planner on the robot's own map.

The tree's steps are not the coverage task's primitive actions: one step drives up to
``ExploreConfig.max_step_m`` and then observes, turning on the way (the base is holonomic). So
here a step is ``max_step_m`` of path and turns cost nothing (one step per move, not 1.7), and the
time left is the episode's steps left.
"""

from __future__ import annotations

from agent.lfe.bellman import Plan, choose_frontier
from agent.lfe.estimator import LearnedEstimator
from agent.mapping.occupancy import ExplorationMap
from agent.planning.frontier_plan import Candidates


def lfe_frontier(world_map: ExplorationMap, robot_xy: tuple[float, float], candidates: Candidates,
                 estimator: LearnedEstimator, steps_left: int, step_length_m: float) -> Plan:
    """The candidate frontier to explore next, with the learned R_A, D_in and D_out.

    Args:
        world_map: the robot's map.
        robot_xy: where the robot stands.
        candidates: the frontiers and the cells the robot may cross.
        estimator: the learned frontier-property estimator.
        steps_left: the episode's steps left (σ; at least 1).
        step_length_m: the length of one forward move.

    Returns:
        The plan.
    """
    properties = estimator.estimate(world_map.free, world_map.occupied, world_map.spec.resolution,
                                    candidates.frontiers)
    robot_cell = tuple(int(v) for v in world_map.spec.to_cell(robot_xy))
    return choose_frontier([p.area_m2 for p in properties], [p.d_in_m for p in properties],
                           [p.d_out_m for p in properties], world_map.spec, candidates.traversable,
                           robot_cell, [f.centre for f in candidates.frontiers], max(steps_left, 1),
                           step_length_m, steps_per_move=1.0)
