"""The EQA episode tree: explore, query the VLM, check confidence, and answer.

::

    EQA episode (selector: until answered)
    ├─ Confident (sequence)         CheckConfidence → Answer
    ├─ Out of budget (sequence)     ShouldStop → AnswerFallback
    └─ Step (sequence, memory)      Observe → IntegrateMap → QueryVLM → UpdatePredictionSet → Act → Next move
                                    Act (selector):       CheckConfidence before act
                                                          or Look inside: LookInside → QueryVLM inside → UpdatePredictionSet
                                                          or Nothing to open
                                    Next move (selector): CheckConfidence before move
                                                          or Go on: [QueryDirections] → Explore
                                    Explore (sequence):   Where to (selector) → Move or finish
                                    Where to (selector):  ApproachStorage or SelectFrontier
                                    Move or finish (sel.): MarkExplorationComplete (no frontier planned)
                                                          or Navigate

The stopping rule (conformal prediction by default) decides in UpdatePredictionSet; a confident
robot skips its next move and answers on the following tick. QueryDirections (the VLM's semantic
values of directions) is there for the semantic methods only. LookInside opens the storage a
question asks what is in, when it is in view, every door and drawer of it, so that the VLM sees
inside (the views side by side, on the blackboard's ``inside_view``: `behaviours.look_inside`);
ApproachStorage, there with the act branch, goes to look at such storage seen farther off before
any frontier is chosen (`behaviours.approach_storage`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import py_trees

from behaviours import blackboard as bb
from agent.mapping.semantic_map import SemanticValueConfig
from agent.planning.frontier_plan import ExploreConfig
from agent.planning.prompt_points import PromptPointConfig
from agent.planning.semantic import FrontierWeightConfig
from agent.timing import StageTimer
from worlds.bus.link import WorldLink
from agent.vlm.protocol import VisionLanguageModel
from agent.eqa.stopping import BudgetRule, StoppingRule
from behaviours.answer import Answer, AnswerFallback, ShouldStop
from behaviours.approach_storage import ApproachStorage
from behaviours.confidence import CheckConfidence, UpdatePredictionSet
from behaviours.select_frontier import MarkExplorationComplete, SelectFrontier
from behaviours.integrate_map import IntegrateMap
from behaviours.look_inside import LookInside, LookInsideConfig
from behaviours.navigate import Navigate
from behaviours.observe import Observe
from behaviours.query_directions import QueryDirections
from behaviours.query_answer import QueryVLM


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
    stopping: StoppingRule = field(default_factory=BudgetRule)
    act: LookInsideConfig | None = field(default_factory=LookInsideConfig)  # None: never open anything


def build_eqa_tree(parts: EqaTreeParts) -> py_trees.behaviour.Behaviour:
    """The EQA tree: answer once confident, fall back to an answer when the budget is spent, else explore a step.

    Args:
        parts: what the leaves share: the world link, the VLM, the exploration settings, the timer,
            the seed, the acting settings.

    Returns:
        The tree's root, ready for `setup` and ticking.
    """
    timer = parts.timer
    confident = py_trees.composites.Sequence(
        "Confident", memory=False, children=[CheckConfidence(), Answer()]
    )
    out_of_budget = py_trees.composites.Sequence(
        "Out of budget", memory=False, children=[ShouldStop(), AnswerFallback()]
    )
    rng = np.random.default_rng([parts.seed, 7])
    move_or_finish = py_trees.composites.Selector(
        "Move or finish", memory=False, children=[MarkExplorationComplete(), Navigate(parts.link, parts.move_timeout_s, timer)]
    )
    where_to: py_trees.behaviour.Behaviour = SelectFrontier(parts.explore, parts.frontier_weights, rng, timer)
    if parts.act is not None:
        where_to = py_trees.composites.Selector("Where to", memory=False, children=[
            ApproachStorage(parts.act.approach, parts.explore), where_to,
        ])
    explore: py_trees.behaviour.Behaviour = py_trees.composites.Sequence("Explore", memory=True, children=[
        where_to, move_or_finish,
    ])
    if parts.explore.strategy.use_semantic:
        directions = QueryDirections(parts.vlm, parts.explore.strategy, rng, parts.prompt_points,
                                     parts.semantic_values, parts.vlm_timeout_s, timer, parts.images_dir)
        explore = py_trees.composites.Sequence("Go on", memory=True, children=[directions, explore])
    next_move = py_trees.composites.Selector(
        "Next move", memory=False, children=[CheckConfidence("CheckConfidence before move"), explore]
    )
    act: list[py_trees.behaviour.Behaviour] = []
    if parts.act is not None:
        look_inside = py_trees.composites.Sequence("Look inside", memory=True, children=[
            LookInside(parts.link, parts.act),
            QueryVLM(parts.vlm, parts.vlm_timeout_s, timer, "QueryVLM inside", view=bb.INSIDE_VIEW),
            UpdatePredictionSet(parts.stopping, "UpdatePredictionSet inside"),
        ])
        act = [py_trees.composites.Selector("Act", memory=False, children=[
            CheckConfidence("CheckConfidence before act"), look_inside, py_trees.behaviours.Success("Nothing to open"),
        ])]
    step = py_trees.composites.Sequence("Step", memory=True, children=[
        Observe(parts.link, timer), IntegrateMap(timer), QueryVLM(parts.vlm, parts.vlm_timeout_s, timer),
        UpdatePredictionSet(parts.stopping), *act, next_move,
    ])
    return py_trees.composites.Selector("EQA episode", memory=False, children=[confident, out_of_budget, step])
