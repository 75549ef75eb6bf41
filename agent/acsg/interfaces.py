"""The three small interfaces the explorer is driven through, and the data that crosses them.

Exploration needs to see (`Perception`), to judge (`DecisionModule`) and to act (`SkillExecutor`).
Keeping each behind a protocol of one or two methods is what lets the same Algorithm 1 run against
a real arm, a simulator, or the symbolic scenes of `agent.acsg.symbolic` in tests.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol

import numpy as np

from agent.acsg.graph import ACSG
from agent.acsg.nodes import ActionNode, ObjectNode

Proposal = Literal["open", "pick", "none"]
PROPOSALS: tuple[str, ...] = ("open", "pick", "none")


def object_id(instance: str | int) -> str:
    """The node id of a perceived instance: the ground truth's ``o<instance>``.

    Args:
        instance: the perceived instance.

    Returns:
        The node id.
    """
    return f"o{instance}"


@dataclass(frozen=True)
class Detection:
    """One object (or part, or handle) the perception sees now.

    ``parent`` and ``relation`` are the spatial hint behind an object-object edge (Algorithm 2):
    the instance this one belongs to, stands on or lies inside. ``hints`` carry geometry the
    verifier may use: ``blocks`` (instances of parts whose motion this object is in the way of),
    ``swept`` ((lo, hi) corners of the box, or (N, 3) corners of the boxes, holding what a part
    sweeps when it opens) or ``box`` ((lo, hi) corners of the box around what was seen of it, where
    ``centroid`` is the mean of its points and not that box's middle); and ``absorbed``, instances
    the perception has since found to be this one (two views of one mug it first took for two
    things), which the explorer folds into this one's node.
    """

    instance: str
    label: str
    parent: str | None = None
    relation: str | None = None
    attributes: Mapping[str, Any] = field(default_factory=dict)
    centroid: np.ndarray | None = None
    extent: np.ndarray | None = None
    hints: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        object.__setattr__(self, "instance", str(self.instance))
        if self.parent is not None:
            object.__setattr__(self, "parent", str(self.parent))
        if not self.label:
            raise ValueError(f"detection {self.instance}: label must be a non-empty string")
        if (self.parent is None) != (self.relation is None):
            raise ValueError(f"detection {self.instance}: parent and relation come together "
                             f"(parent={self.parent!r}, relation={self.relation!r})")

    @property
    def id(self) -> str:
        return object_id(self.instance)


@dataclass(frozen=True)
class SkillCall:
    """One primitive to run: ``primitive`` (a `primitives.PRIMITIVES` name) on the object ``target``
    (a node id; ``instance`` is the perception's id for it), for the ACSG action ``action``."""

    primitive: str
    action: str
    target: str
    instance: str | None
    params: Mapping[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class SkillResult:
    ok: bool
    reason: str = ""


@dataclass(frozen=True)
class DecisionContext:
    """What the decision module may look at: the graph so far, what is in view now (node id ->
    detection), and the objects the explorer has moved to the idle space."""

    graph: ACSG
    visible: Mapping[str, Detection]
    moved_away: frozenset[str] = frozenset()


class Perception(Protocol):
    def observe(self) -> list[Detection]:
        """Everything detected in the current views (called after every action).

        Returns:
            The detections.
        """
        ...


class DecisionModule(Protocol):
    def propose(self, obj: ObjectNode, context: DecisionContext) -> Proposal:
        """The proposer: how to explore ``obj``: "open" its doors or drawers, "pick" it up, or "none".

        Args:
            obj: the object judged.
            context: the graph and what is in view.

        Returns:
            "open", "pick" or "none".
        """
        ...

    def verify(self, action: ActionNode, context: DecisionContext) -> list[str]:
        """The verifier: node ids of the objects that block ``action`` now (empty when it can run).

        Args:
            action: the action judged.
            context: the graph and what is in view.

        Returns:
            The blockers' node ids.
        """
        ...


class SkillExecutor(Protocol):
    def execute(self, call: SkillCall) -> SkillResult:
        """Run one primitive; a failure says why.

        Args:
            call: the primitive and what it acts on.

        Returns:
            How it went.
        """
        ...
