"""A way through joint space around what stands near, for free moves the straight routes fail.

The arm's free moves go straight in joint space, or with the lift raised, or folded in by way of
the ready pose (`skills.arm.plan_builder.PlanBuilder.free_move`). Reaching into a cabinet whose
door stands open beside it from where the hand let go of that door, every such route swept the
hand through the door. `connect` searches for a way with RRT-Connect (two trees grown towards
random configurations and towards each other, each edge checked at a fine joint step), and
`shortcut` straightens the way it finds, so that the arm moves through a few waypoints rather than
wandering.

Pure: joint vectors and a validity test in, waypoints out. Every random choice is drawn from the
generator passed in.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

#: The most a tree grows towards a sample in one step (rad or m, the largest joint's change).
GROW_STEP = 0.15
#: The finest joint step at which an edge is checked (rad or m). Out at the hand, 0.85 m from the
#: shoulder, it moves the hand by less than the 1 cm the arm keeps from what stands near
#: (`skills.arm.clearance.CLEARANCE_M`), so nothing that thin is stepped over between two checks.
#: At 0.04 rad (3.4 cm) the way found from a cabinet door's handle to high above a carton beside
#: the cabinet skimmed the door; its trajectory, checked densely, was refused, the straight move
#: was taken unchecked, and a finger struck the door (occlusion 1021 of tuning-wide).
EDGE_STEP = 0.01
#: Samples drawn before giving up, and shortcuts tried on a way found.
MAX_SAMPLES, SHORTCUTS = 600, 60

Valid = Callable[[np.ndarray], bool]
#: A tree of configurations: its nodes, and each node's parent's index (-1 for the root).
Tree = tuple[list[np.ndarray], list[int]]


def edge_clear(a: np.ndarray, b: np.ndarray, valid: Valid, step: float = EDGE_STEP) -> bool:
    """Whether the straight joint-space move from ``a`` to ``b`` is valid all the way (``a`` itself
    is not checked).

    Args:
        a: where the move starts.
        b: where it ends.
        valid: the test of one configuration.
        step: the largest joint change between the configurations checked.

    Returns:
        True when every configuration checked passes.
    """
    count = max(1, math.ceil(float(np.abs(b - a).max()) / step))
    return all(valid(a + (b - a) * k / count) for k in range(1, count + 1))


def connect(start: np.ndarray, goal: np.ndarray, valid: Valid, lower: np.ndarray, upper: np.ndarray,
            rng: np.random.Generator, max_samples: int = MAX_SAMPLES) -> list[np.ndarray] | None:
    """A way from ``start`` to ``goal`` through valid configurations (RRT-Connect).

    Args:
        start: where the arm is (not checked: the arm may stand touching what it let go of).
        goal: where it is to go (checked).
        valid: the test of one configuration.
        lower: the joints' lower limits.
        upper: the joints' upper limits.
        rng: the generator every sample is drawn from.
        max_samples: samples drawn before giving up.

    Returns:
        The waypoints, ``start`` first and ``goal`` last, or None when none was found.
    """
    start, goal = np.asarray(start, dtype=float), np.asarray(goal, dtype=float)
    if not valid(goal):
        return None
    if edge_clear(start, goal, valid):
        return [start, goal]
    from_start: Tree = ([start], [-1])
    from_goal: Tree = ([goal], [-1])
    grown, other = from_start, from_goal
    for _ in range(max_samples):
        reached = _extend(grown, rng.uniform(lower, upper), valid)
        if reached is not None:
            met = _reach(other, grown[0][reached], valid)
            if met is not None:
                ends = (reached, met) if grown is from_start else (met, reached)
                return _branch(from_start, ends[0])[::-1] + _branch(from_goal, ends[1])[1:]
        grown, other = other, grown
    return None


def shortcut(path: list[np.ndarray], valid: Valid, rng: np.random.Generator, tries: int = SHORTCUTS
             ) -> list[np.ndarray]:
    """``path`` with stretches between two of its waypoints replaced by straight moves where those are valid.

    Args:
        path: the waypoints, start first.
        valid: the test of one configuration.
        rng: the generator the stretches are drawn from.
        tries: stretches tried.

    Returns:
        The shorter way, with the same ends.
    """
    path = list(path)
    for _ in range(tries):
        if len(path) <= 2:
            break
        i, j = sorted(int(k) for k in rng.choice(len(path), size=2, replace=False))
        if j - i > 1 and edge_clear(path[i], path[j], valid):
            path = path[:i + 1] + path[j:]
    return path


def _extend(tree: Tree, sample: np.ndarray, valid: Valid) -> int | None:
    """One step of ``tree`` from its node nearest ``sample`` towards it; the new node's index."""
    nodes, parents = tree
    nearest = int(np.argmin([float(np.abs(node - sample).max()) for node in nodes]))
    base = nodes[nearest]
    gap = sample - base
    reach = float(np.abs(gap).max())
    new = sample if reach <= GROW_STEP else base + gap * GROW_STEP / reach
    if not edge_clear(base, new, valid):
        return None
    nodes.append(new)
    parents.append(nearest)
    return len(nodes) - 1


def _reach(tree: Tree, target: np.ndarray, valid: Valid) -> int | None:
    """Grow ``tree`` step by step towards ``target`` until it gets there (its node's index) or is stopped."""
    nodes, _ = tree
    while True:
        index = _extend(tree, target, valid)
        if index is None:
            return None
        if float(np.abs(nodes[index] - target).max()) < 1e-9:
            return index


def _branch(tree: Tree, index: int) -> list[np.ndarray]:
    """The nodes from ``index`` back to the tree's root, in that order."""
    nodes, parents = tree
    branch = []
    while index >= 0:
        branch.append(nodes[index])
        index = parents[index]
    return branch
