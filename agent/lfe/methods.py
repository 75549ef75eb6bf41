"""The exploration methods of the paper's Table I, as frontier choosers for the coverage task.

- ``fbe-near``: the nearest frontier (classical FBE).
- ``greedy``: the frontier with the largest learned R_A (PONI-Greedy).
- ``lfe``: the Bellman recursion over learned R_A, D_in and D_out (LFE-UNet).
- ``lfe-oracle``: the same recursion over the true values (LFE-(R°, D°)): an upper bound, since it
  reads the ground truth; it exists for the evaluation only.

A method is built from a *property source*, which gives each offered frontier its R_A, D_in and
D_out, and a *rule* that turns them into a choice. Keeping the two apart is what lets the oracle
and the network share one planner, so that the gap between them is the network's alone.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import nullcontext
from enum import StrEnum

from agent.lfe.bellman import choose_frontier, greedy
from agent.lfe.coverage import fbe_near
from agent.lfe.estimator import LearnedEstimator
from agent.lfe.properties import FrontierProperties, label_frontiers
from agent.lfe.task import CoverageConfig, FrontierChooser, Situation, TrueHome
from agent.timing import StageTimer

PropertySource = Callable[[Situation], list[FrontierProperties]]


class Method(StrEnum):
    """The methods of the paper's Table I, by the names the command line and the result rows use."""

    LFE = "lfe"
    LFE_ORACLE = "lfe-oracle"
    GREEDY = "greedy"
    FBE_NEAR = "fbe-near"


def learned(estimator: LearnedEstimator) -> PropertySource:
    """R_A, D_in and D_out as the network predicts them from the partial map.

    Args:
        estimator: the trained network.

    Returns:
        The property source of the learned methods.
    """

    def source(situation: Situation) -> list[FrontierProperties]:
        return estimator.estimate(situation.free, situation.occupied, situation.spec.resolution, situation.frontiers)

    return source


def oracle(home: TrueHome) -> PropertySource:
    """The true R_A, D_in and D_out, from the home's ground truth and what has been observed.

    Args:
        home: the ground truth the oracle reads.

    Returns:
        The property source of ``lfe-oracle``.
    """

    def source(situation: Situation) -> list[FrontierProperties]:
        return label_frontiers(home.free, situation.observed, situation.frontiers, situation.spec.resolution)

    return source


def bellman_chooser(source: PropertySource, step_length_m: float, timer: StageTimer | None = None) -> FrontierChooser:
    """The frontier whose best sequence of visits reveals the most area in the steps left (Eq. 4).

    Args:
        source: gives each offered frontier its R_A, D_in and D_out.
        step_length_m: the length of a forward move, to count path lengths in steps.
        timer: times each planning step's parts: "properties", "distances" and "recursion".

    Returns:
        The chooser.
    """

    def choose(situation: Situation) -> int:
        with timer.measure("properties") if timer else nullcontext():
            properties = source(situation)
        return choose_frontier([p.area_m2 for p in properties], [p.d_in_m for p in properties],
                               [p.d_out_m for p in properties], situation.spec, situation.traversable,
                               situation.robot_cell, [f.centre for f in situation.frontiers], situation.steps_left,
                               step_length_m, timer=timer).choice

    return choose


def greedy_chooser(source: PropertySource) -> FrontierChooser:
    """The frontier with the largest R_A, however far it is.

    Args:
        source: gives each offered frontier its R_A.

    Returns:
        The chooser.
    """

    def choose(situation: Situation) -> int:
        return greedy([p.area_m2 for p in source(situation)])

    return choose


def make_chooser(method: Method | str, home: TrueHome, estimator: LearnedEstimator | None,
                 config: CoverageConfig = CoverageConfig()) -> FrontierChooser:
    """The chooser of ``method`` for one episode in ``home``.

    Args:
        method: which method.
        home: the episode's ground truth (read by the oracle only).
        estimator: the network; the learned methods need it.
        config: the move's length.

    Returns:
        The chooser.

    Raises:
        ValueError: an unknown method, or a learned one without ``estimator``.
    """
    method = Method(method)
    if method is Method.FBE_NEAR:
        return fbe_near
    if method is Method.LFE_ORACLE:
        return bellman_chooser(oracle(home), config.forward_m)
    if estimator is None:
        raise ValueError(f"method {method.value!r} needs a trained estimator")
    if method is Method.GREEDY:
        return greedy_chooser(learned(estimator))
    return bellman_chooser(learned(estimator), config.forward_m)
