"""The EQA episode tree: explore, query the VLM, and answer when the budget is spent.

::

    EQA episode (selector: until answered)
    ├─ Out of budget (sequence)     BudgetSpent → AnswerFallback
    └─ Step (sequence, memory)      Observe → IntegrateMap → QueryVLM → [QueryDirections] → Next move
                                    Next move (selector): Explore (SelectFrontier → Navigate)
                                                          or NothingLeftToExplore

QueryDirections (the VLM's semantic values of directions) is there for the semantic methods only.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import py_trees

from agent.mapping.semantic_map import SemanticValueConfig
from agent.planning.explore import ExploreConfig
from agent.planning.prompt_points import PromptPointConfig
from agent.planning.semantic import FrontierWeightConfig, method_flags
from agent.runtime.timing import StageTimer
from agent.runtime.world_link import WorldLink
from agent.vlm.protocol import VisionLanguageModel
from behaviours.answer import AnswerFallback, ShouldStop
from behaviours.explore import MarkExplorationComplete, SelectFrontier
from behaviours.integrate_map import IntegrateMap
from behaviours.navigate import Navigate
from behaviours.observe import Observe
from behaviours.query_directions import QueryDirections
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
    prompt_points: PromptPointConfig = field(default_factory=PromptPointConfig)
    semantic_values: SemanticValueConfig = field(default_factory=SemanticValueConfig)
    frontier_weights: FrontierWeightConfig = field(default_factory=FrontierWeightConfig)
    seed: int = 0  # seeds prompt-point sampling and frontier sampling
    images_dir: Path | None = None  # where the annotated images of visual prompts are saved


def build_eqa_tree(parts: EqaTreeParts) -> py_trees.behaviour.Behaviour:
    timer = parts.timer
    out_of_budget = py_trees.composites.Sequence(
        "Out of budget", memory=False, children=[ShouldStop(), AnswerFallback()]
    )
    rng = np.random.default_rng([parts.seed, 7])
    explore = py_trees.composites.Sequence(
        "Explore", memory=True,
        children=[SelectFrontier(parts.explore, parts.frontier_weights, rng, timer),
                  Navigate(parts.link, parts.move_timeout_s)],
    )
    next_move = py_trees.composites.Selector(
        "Next move", memory=False, children=[explore, MarkExplorationComplete()]
    )
    leaves = [Observe(parts.link, timer), IntegrateMap(timer), QueryVLM(parts.vlm, parts.vlm_timeout_s, timer)]
    if method_flags(parts.explore.method).use_semantic:
        leaves.append(QueryDirections(parts.vlm, parts.explore.method, rng, parts.prompt_points,
                                      parts.semantic_values, parts.vlm_timeout_s, timer, parts.images_dir))
    step = py_trees.composites.Sequence("Step", memory=True, children=[*leaves, next_move])
    return py_trees.composites.Selector("EQA episode", memory=False, children=[out_of_budget, step])
