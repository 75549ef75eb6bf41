"""The EQA episode tree: explore, query the VLM, and answer when the budget is spent.

::

    EQA episode (selector: until answered)
    ├─ Out of budget (sequence)     BudgetSpent → AnswerFallback
    └─ Step (sequence, memory)      Observe → IntegrateMap → QueryVLM → Next move
                                    Next move (selector): Explore (SelectFrontier → Navigate)
                                                          or NothingLeftToExplore
"""

from __future__ import annotations

from dataclasses import dataclass

import py_trees

from agent.planning.explore import ExploreConfig
from agent.runtime.timing import StageTimer
from agent.runtime.world_link import WorldLink
from agent.vlm.protocol import VisionLanguageModel
from behaviours.answer import AnswerFallback, ShouldStop
from behaviours.explore import MarkExplorationComplete, SelectFrontier
from behaviours.integrate_map import IntegrateMap
from behaviours.navigate import Navigate
from behaviours.observe import Observe
from behaviours.query_vlm import QueryVLM


@dataclass(frozen=True)
class EqaTreeParts:
    """What the EQA tree's leaves need from outside the blackboard."""

    link: WorldLink
    vlm: VisionLanguageModel
    explore: ExploreConfig = ExploreConfig()
    vlm_timeout_s: float = 30.0
    move_timeout_s: float = 30.0
    timer: StageTimer | None = None


def build_eqa_tree(parts: EqaTreeParts) -> py_trees.behaviour.Behaviour:
    timer = parts.timer
    out_of_budget = py_trees.composites.Sequence(
        "Out of budget", memory=False, children=[ShouldStop(), AnswerFallback()]
    )
    explore = py_trees.composites.Sequence(
        "Explore", memory=True,
        children=[SelectFrontier(parts.explore, timer), Navigate(parts.link, parts.move_timeout_s)],
    )
    next_move = py_trees.composites.Selector(
        "Next move", memory=False, children=[explore, MarkExplorationComplete()]
    )
    step = py_trees.composites.Sequence(
        "Step", memory=True,
        children=[
            Observe(parts.link, timer),
            IntegrateMap(timer),
            QueryVLM(parts.vlm, parts.vlm_timeout_s, timer),
            next_move,
        ],
    )
    return py_trees.composites.Selector("EQA episode", memory=False, children=[out_of_budget, step])
