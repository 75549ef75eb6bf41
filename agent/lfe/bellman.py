"""Choosing a frontier with the Bellman equation of learning-augmented frontier exploration.

Each frontier ``a`` is an action worth its area ``R_A`` beyond, reached after ``D_k`` steps through
known space, explored in ``D_in`` steps and left in ``D_out`` more (paper Eq. 4 and 5)::

    Q(q, A, σ, a) = R_A(a)·min(1, (σ − D_k(q, a)) / D_in(a))
                    + max over a' ∈ A∖{a} of Q(q_a, A∖{a}, σ − D_k(q, a) − D_in(a) − D_out(a), a')

An action the robot cannot reach in the time left (σ − D_k ≤ 0) is worth nothing and ends the
recursion there: rewards are never negative. The recursion runs over the few frontiers with the
largest R_A (six in the paper), which keeps it at a few thousand evaluations.

Everything here is in steps. The known-space distances come as one matrix computed once per
planning step (`distance_matrix`, one geodesic distance field per source); the recursion only
looks them up, where the paper's reference code re-plans every path on every branch.
"""

from __future__ import annotations

from collections.abc import Sequence
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from agent.mapping.grid import GridSpec
from agent.planning.paths import distance_field
from agent.timing import StageTimer

STEPS_PER_MOVE = 1.7
"""Time steps per forward move, turns included: the paper's empirical distance-to-steps ratio."""

PLANNED_FRONTIERS = 6
"""How many frontiers (those with the largest R_A) the recursion considers, as in the paper."""

_TIE = 1e-9  # relative tolerance under which two values count as equal


def metres_to_steps(metres: ArrayLike, step_length_m: float, steps_per_move: float = STEPS_PER_MOVE) -> np.ndarray:
    """Distances in metres as time steps: forward moves of ``step_length_m``, times the turn factor.

    The paper plans in steps but measures distances on the grid; 1.7 steps per forward move
    accounts for the turns a differential robot makes along a grid path.

    Args:
        metres: the distances (m).
        step_length_m: the length of one forward move.
        steps_per_move: the turn factor.

    Returns:
        The distances in steps.

    Raises:
        ValueError: the step length is not positive.
    """
    if not step_length_m > 0:
        raise ValueError(f"step_length_m must be positive, got {step_length_m}")
    return np.asarray(metres, dtype=float) / step_length_m * steps_per_move


def distance_matrix(spec: GridSpec, traversable: np.ndarray, sources: Sequence[tuple[int, int]],
                    cell_cost: np.ndarray | None = None) -> np.ndarray:
    """Known-space path lengths in metres between the robot and the frontiers, as an (N, N) matrix.

    ``sources`` are cells (row, col): the robot first, then each frontier's centre. Entry [i, j] is
    the length of the shortest 8-connected path over ``traversable`` from source i to source j
    (inf where there is none). One distance field per source, so N Dijkstra runs in all, done once
    per planning step. The matrix need not be symmetric: a start cell counts as traversable
    whatever the mask says (the robot stands there), so a frontier centre inside the clearance
    margin can be left but not entered.

    Args:
        spec: the grid.
        traversable: the cells the robot may cross (bool, the grid's shape).
        sources: the robot's cell, then each frontier's centre.
        cell_cost: each cell's weight (1 everywhere when None).

    Returns:
        The (N, N) matrix (m).

    Raises:
        ValueError: the mask is not bool or not the grid's shape.
    """
    traversable = np.asarray(traversable)
    if traversable.dtype != bool:
        raise ValueError(f"traversable must be a bool mask, got dtype {traversable.dtype}")
    if traversable.shape != spec.shape:
        raise ValueError(f"traversable has shape {traversable.shape}, the grid {spec.shape}")
    cells = np.asarray(sources, dtype=int).reshape(-1, 2)
    if len(cells) == 0:
        raise ValueError("sources is empty: it needs at least the robot's cell")
    if not spec.inside(cells).all():
        raise ValueError(f"sources has cells outside the grid {spec.shape}: {cells[~spec.inside(cells)].tolist()}")
    matrix = np.empty((len(cells), len(cells)))
    for i, start in enumerate(cells):
        field = distance_field(spec, traversable, (int(start[0]), int(start[1])), cell_cost)
        matrix[i] = field.metres[cells[:, 0], cells[:, 1]]
    np.fill_diagonal(matrix, 0.0)
    return matrix


@dataclass(frozen=True)
class Plan:
    """The planner's answer: which frontier to explore now, what the best plan is worth, and why."""

    choice: int  # index into the frontier arrays
    value: float  # Q of the choice: the area (same unit as R_A) the best sequence reveals in time
    sequence: tuple[int, ...]  # the best order of visits, starting with the choice, while time lasts
    q_values: np.ndarray  # Q of every frontier as the first action; nan for those not planned over


def largest(area: ArrayLike, k: int = PLANNED_FRONTIERS) -> np.ndarray:
    """Indices of the ``k`` frontiers with the largest R_A, largest first (ties: lower index first).

    Callers can select with this before computing the distance matrix, so that only k + 1
    distance fields are needed.

    Args:
        area: R_A per frontier.
        k: how many to keep.

    Returns:
        The indices.
    """
    area = _vector(area, "area")
    return np.argsort(-area, kind="stable")[:k]


def plan(area: ArrayLike, d_in: ArrayLike, d_out: ArrayLike, distances: ArrayLike, sigma: float,
         max_frontiers: int = PLANNED_FRONTIERS) -> Plan:
    """The frontier that maximises Q (paper Eq. 4), over the ``max_frontiers`` with the largest R_A.

    ``area``, ``d_in`` and ``d_out`` hold R_A, D_in and D_out per frontier (K each, D in steps);
    ``distances`` is the (K + 1, K + 1) known-space matrix in steps with the robot first
    (`distance_matrix`, then `metres_to_steps`); ``sigma`` is the number of steps left.

    Among actions of equal Q the one that leaves more steps after it (σ − D_k − D_in − D_out) wins,
    as in the paper, then the lower index. There is no memoisation: σ after a prefix depends on its
    order, so (node, remaining set, σ) almost never repeats, and the six-frontier tree is only
    1956 evaluations.

    Args:
        area: R_A per frontier.
        d_in: D_in per frontier (steps).
        d_out: D_out per frontier (steps).
        distances: the known-space distances (steps), robot first.
        sigma: the steps left.
        max_frontiers: how many frontiers enter the recursion.

    Returns:
        The plan: the choice, its sequence and the Q values.

    Raises:
        ValueError: arrays of the wrong shape or with nan.
    """
    area = _vector(area, "area")
    d_in = _vector(d_in, "d_in", len(area))
    d_out = _vector(d_out, "d_out", len(area))
    distances = np.asarray(distances, dtype=float)
    if distances.shape != (len(area) + 1, len(area) + 1):
        raise ValueError(f"distances must be ({len(area) + 1}, {len(area) + 1}) with the robot first, "
                         f"got {distances.shape}")
    if np.isnan(distances).any() or (distances < 0).any():
        raise ValueError("distances must be non-negative (inf for unreachable), with no nan")
    if not np.isfinite(sigma):
        raise ValueError(f"sigma must be a finite number of steps, got {sigma}")
    if max_frontiers < 1:
        raise ValueError(f"max_frontiers must be at least 1, got {max_frontiers}")

    chosen = np.sort(largest(area, max_frontiers))  # in index order, so that full ties go to the lower
    nodes = np.concatenate([[0], chosen + 1])
    recursion = _Recursion(area[chosen].tolist(), d_in[chosen].tolist(), d_out[chosen].tolist(),
                           distances[np.ix_(nodes, nodes)].tolist())
    q_values = np.full(len(area), np.nan)
    best: tuple[float, float, tuple[int, ...]] | None = None
    best_action = -1
    for action in range(len(chosen)):  # node 0 is the robot; action i is node i + 1
        outcome = recursion.q(action, 0, tuple(range(len(chosen))), float(sigma))
        q_values[chosen[action]] = outcome[0]
        if best is None or _better(outcome, best):
            best, best_action = outcome, action
    assert best is not None
    sequence = tuple(int(chosen[i]) for i in best[2]) or (int(chosen[best_action]),)
    return Plan(int(chosen[best_action]), best[0], sequence, q_values)


def choose_frontier(area: ArrayLike, d_in_m: ArrayLike, d_out_m: ArrayLike, spec: GridSpec, traversable: np.ndarray,
                    robot_cell: tuple[int, int], centres: Sequence[tuple[int, int]], sigma: float,
                    step_length_m: float, steps_per_move: float = STEPS_PER_MOVE,
                    timer: StageTimer | None = None) -> Plan:
    """One whole planning step: the frontier to explore, from properties in metres and a map.

    Only the ``PLANNED_FRONTIERS`` with the largest R_A enter the recursion, so only their
    known-space distances (and the robot's) are computed: seven distance fields, once. The plan's
    indices (``choice``, ``sequence``, ``q_values``) are into the full arrays. ``timer`` times the
    two parts, "distances" and "recursion" (`homebot bench plan`).

    Args:
        area: R_A per frontier (m²).
        d_in_m: D_in per frontier (m).
        d_out_m: D_out per frontier (m).
        spec: the grid.
        traversable: the cells the robot may cross.
        robot_cell: the robot's cell (row, col).
        centres: each frontier's centre cell.
        sigma: the steps left.
        step_length_m: the length of one forward move.
        steps_per_move: the turn factor.
        timer: times the two parts, if given.

    Returns:
        The plan.
    """
    area = _vector(area, "area")
    chosen = largest(area)
    cells = [tuple(robot_cell)] + [tuple(centres[i]) for i in chosen]
    with timer.measure("distances") if timer else nullcontext():
        distances = metres_to_steps(distance_matrix(spec, traversable, cells), step_length_m, steps_per_move)
    d_in = metres_to_steps(_vector(d_in_m, "d_in_m", len(area))[chosen], step_length_m, steps_per_move)
    d_out = metres_to_steps(_vector(d_out_m, "d_out_m", len(area))[chosen], step_length_m, steps_per_move)
    with timer.measure("recursion") if timer else nullcontext():
        best = plan(area[chosen], d_in, d_out, distances, sigma)
    q_values = np.full(len(area), np.nan)
    q_values[chosen] = best.q_values
    return Plan(int(chosen[best.choice]), best.value, tuple(int(chosen[i]) for i in best.sequence), q_values)


def greedy(area: ArrayLike) -> int:
    """The frontier with the largest R_A (PONI-Greedy, Greedy-R°); ties go to the lower index.

    Args:
        area: R_A per frontier.

    Returns:
        The frontier's index.
    """
    return int(np.argmax(_vector(area, "area")))


def nearest(from_robot: ArrayLike) -> int:
    """The frontier with the smallest D_k (FBE-Near); ties go to the lower index.

    Args:
        from_robot: D_k per frontier.

    Returns:
        The frontier's index.

    Raises:
        ValueError: no distance, a nan, or no frontier reachable.
    """
    from_robot = np.asarray(from_robot, dtype=float)
    if from_robot.ndim != 1 or len(from_robot) == 0 or np.isnan(from_robot).any():
        raise ValueError(f"from_robot must be a non-empty 1-D array without nan, got shape {from_robot.shape}")
    if not np.isfinite(from_robot).any():
        raise ValueError("from_robot has no reachable frontier (all distances are inf)")
    return int(np.argmin(from_robot))


class _Recursion:
    """Eq. 4 over plain lists (faster than numpy indexing for scalars); actions are 0..n-1, nodes
    are 0 for the robot and action + 1 for a frontier."""

    def __init__(self, area: list[float], d_in: list[float], d_out: list[float], dist: list[list[float]]):
        self.area, self.d_in, self.d_out, self.dist = area, d_in, d_out, dist

    def q(self, action: int, node: int, remaining: tuple[int, ...], sigma: float) -> tuple[float, float, tuple[int, ...]]:
        """(Q, steps left after the action, best sequence from it) for taking ``action`` at ``node``."""
        left = sigma - self.dist[node][action + 1]
        after = left - self.d_in[action] - self.d_out[action]
        if left <= 0:
            return 0.0, after, ()
        d_in = self.d_in[action]
        gain = self.area[action] * (1.0 if d_in <= 0 else min(1.0, left / d_in))
        rest = tuple(a for a in remaining if a != action)
        if after <= 0 or not rest:
            return gain, after, (action,)
        best: tuple[float, float, tuple[int, ...]] | None = None
        for following in rest:
            outcome = self.q(following, action + 1, rest, after)
            if best is None or _better(outcome, best):
                best = outcome
        assert best is not None
        return gain + best[0], after, (action,) + (best[2] if best[0] > 0 else ())


def _better(candidate: tuple[float, float, tuple[int, ...]], incumbent: tuple[float, float, tuple[int, ...]]) -> bool:
    """Larger Q wins; equal Q (within a relative 1e-9) goes to more steps left; else the incumbent."""
    value, best = candidate[0], incumbent[0]
    tolerance = _TIE * max(1.0, abs(value), abs(best))
    if value > best + tolerance:
        return True
    return value >= best - tolerance and candidate[1] > incumbent[1]


def _vector(values: ArrayLike, name: str, length: int | None = None) -> np.ndarray:
    """A finite, non-negative 1-D float array, non-empty and of ``length`` when given."""
    array = np.asarray(values, dtype=float)
    if array.ndim != 1 or len(array) == 0:
        raise ValueError(f"{name} must be a non-empty 1-D array, got shape {array.shape}")
    if length is not None and len(array) != length:
        raise ValueError(f"{name} has {len(array)} entries, area has {length}")
    if not np.isfinite(array).all() or (array < 0).any():
        raise ValueError(f"{name} must be finite and non-negative")
    return array
