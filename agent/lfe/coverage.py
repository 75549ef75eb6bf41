"""The coverage task of learning-augmented frontier exploration on a 2-D grid (paper §IV, §VI-A).

A robot with a panoramic range sensor explores a home for a budget of primitive actions (forward
0.25 m, turn ±30°; 500 of them) and is scored by the share of the home's free floor it has seen.
Every few steps a *chooser* picks one of the reachable frontiers from what the robot knows; the
simulator drives there with primitive actions, sensing after each, until it is time to choose
again. The chooser is the only thing the methods of the paper's Table I differ in.

The task's terms (its numbers, the ground truth, the chooser's view) are in `agent.lfe.task`, the
motion model in `agent.lfe.motion`, and what the robot knows and how it drives in
`agent.lfe.grid_robot`; here is the loop that joins them.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from agent.lfe.bellman import nearest
from agent.lfe.grid_robot import GridRobot, Route
from agent.lfe.motion import next_action
from agent.lfe.task import CoverageConfig, CoverageResult, FrontierChooser, Situation, TrueHome


def fbe_near(situation: Situation) -> int:
    """FBE-Near: the nearest frontier, the classical baseline.

    Args:
        situation: the chooser's view.

    Returns:
        The index of the frontier with the shortest known-space path (ties: the lower index).
    """
    return nearest(situation.from_robot_m)


def run_coverage(home: TrueHome, choose: FrontierChooser, config: CoverageConfig = CoverageConfig(),
                 on_plan: Callable[[Situation, int], None] | None = None) -> CoverageResult:
    """Explore ``home`` for ``config.budget_steps`` primitive actions, choosing frontiers with ``choose``.

    A frontier is chosen at the start, every ``replan_every`` steps, when the robot reaches the
    goal or its goal stops being a frontier, and after a blocked move. The run ends when the budget
    is spent or no reachable frontier is left. Nothing here is random: the same home, chooser and
    config give the same result.

    Args:
        home: the ground truth to explore.
        choose: picks a frontier at each planning step.
        config: the task's numbers; its resolution must be the home's.
        on_plan: hears of every choice as ``on_plan(situation, index)``.

    Returns:
        The coverage after each step, the poses and the planning statistics.

    Raises:
        ValueError: the home's grid is not at the config's resolution, or ``choose`` returned no
            index into the frontiers.
    """
    if home.spec.resolution != config.resolution:
        raise ValueError(f"home: its grid is at {home.spec.resolution:g} m, the config's at {config.resolution:g} m")
    robot = GridRobot(home, config)
    coverage = [robot.coverage()]
    poses = [robot.pose]
    plan_seconds: list[float] = []
    frontier_counts: list[int] = []
    blocked_steps: list[int] = []
    route: Route | None = None
    since_plan = 0
    exhausted = False
    while len(coverage) <= config.budget_steps:
        steps_left = config.budget_steps - len(coverage) + 1
        keep = route is not None and since_plan < config.replan_every and robot.is_frontier(route.goal)
        target = route.target(robot.pose) if keep and route is not None else None
        if target is None:
            situation = robot.situation(steps_left)
            if situation is None:
                exhausted = True
                break
            started = time.perf_counter()
            index = choose(situation)
            plan_seconds.append(time.perf_counter() - started)
            frontier_counts.append(len(situation.frontiers))
            if not 0 <= index < len(situation.frontiers):
                raise ValueError(f"choose: returned {index}, not an index into {len(situation.frontiers)} frontiers")
            if on_plan is not None:
                on_plan(situation, index)
            route = robot.route_to(situation.frontiers[index])
            since_plan = 0
            target = route.target(robot.pose)
            assert target is not None, "an offered frontier lies farther than one move"
        blocked = robot.act(next_action(robot.pose, target, config))
        since_plan = config.replan_every if blocked else since_plan + 1
        if blocked:
            blocked_steps.append(len(coverage))
        coverage.append(robot.coverage())
        poses.append(robot.pose)
    padded = np.concatenate([coverage, np.full(config.budget_steps + 1 - len(coverage), coverage[-1])])
    return CoverageResult(padded, len(coverage) - 1, exhausted, plan_seconds, frontier_counts,
                          np.array(poses, dtype=float), blocked_steps)
