"""The EQA tree's blackboard contract: every key, its type, who writes and who reads it, and how an
episode's board starts, declared in one place so that behaviours and the runtime agree on it.

Leaves register each key with the access they use: a leaf that changes an object on the board in
place (fuses a frame into the map, appends to the trajectory) registers WRITE, as a leaf that sets
the key does. `seed_board` puts the initial values of one episode on the board, and
`contract_problems` says where a board, or the leaves of a tree, break the contract: the runtime
checks the board at the end of every episode, and tests/test_blackboard_contract.py checks every
leaf's registrations.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import py_trees
from py_trees.common import Access

from agent.eqa.answers import AnswerLog
from agent.eqa.stopping import StopDecision
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.mapping.semantic_map import SemanticMap, SemanticValueConfig
from agent.observation import Observation
from agent.planning.frontier_plan import MovePlan
from agent.planning.explore_method import ExploreStrategy
from agent.planning.map_fields import MapFields
from agent.pose import Pose2D
from behaviours.episode_state import ApproachState, LookInsideState

QUESTION = "question"
CHOICES = "choices"
BUDGET = "budget"
OBSERVATION = "observation"
INSIDE_VIEW = "inside_view"
MAP = "map"
MAP_FIELDS = "map_fields"
ANSWER_LOG = "answer_log"
PLAN = "plan"
FRONTIER_GOAL = "frontier_goal"
TRAJECTORY = "trajectory"
EXPLORATION_COMPLETE = "exploration_complete"
ANSWER = "answer"
SEMANTIC_MAP = "semantic_map"
STOP_DECISION = "stop_decision"
PREDICTION_SET = "prediction_set"
Q_HAT = "q_hat"
EPSILON = "epsilon"
ACTS = "acts"
APPROACH_STATE = "approach_state"
LOOK_INSIDE_STATE = "look_inside_state"
FRONTIER_CHOICES = "frontier_choices"
DIRECTION_PROMPTS = "direction_prompts"


@dataclass(frozen=True)
class KeySpec:
    """One key of the contract: what it holds (``type``, described in ``about``), who writes it,
    who reads it (class names of leaves, or the node name where one class appears twice; the runtime's
    ``EpisodeRunner`` and ``Recorder`` read from outside the tree), and how
    an episode starts it ("" for keys a leaf writes first)."""

    type: type | tuple[type, ...]
    about: str
    writers: tuple[str, ...]
    readers: tuple[str, ...]
    initial: str


#: The EQA tree's keys. Writers include leaves that change the object in place.
CONTRACT: dict[str, KeySpec] = {
    QUESTION: KeySpec(str, "str", ("EpisodeSetup",), ("QueryVLM", "QueryDirections", "ApproachStorage", "LookInside"),
                      "the scenario's question"),
    CHOICES: KeySpec(list, "list[str], four, padded", ("EpisodeSetup",), ("QueryVLM", "Answer", "AnswerFallback"),
                     "the scenario's choices"),
    BUDGET: KeySpec(int, "int, steps", ("EpisodeSetup",), ("ShouldStop", "SelectFrontier"), "episode.budget or the scenario's"),
    OBSERVATION: KeySpec(Observation, "agent.observation.Observation, the newest frame", ("Observe", "LookInside"),
                         ("IntegrateMap", "QueryVLM", "QueryDirections", "ApproachStorage", "SelectFrontier",
                          "LookInside"), ""),
    INSIDE_VIEW: KeySpec(Observation, "agent.observation.Observation, the views into storage just opened", ("LookInside",),
                         ("QueryVLM inside",), ""),
    MAP: KeySpec(ExplorationMap, "agent.mapping.occupancy.ExplorationMap", ("EpisodeSetup", "IntegrateMap", "Navigate"),
                 ("QueryDirections", "ApproachStorage", "SelectFrontier", "LookInside"), "empty, laid round the start"),
    MAP_FIELDS: KeySpec(MapFields, "agent.planning.map_fields.MapFields, the map's clearance and drive fields",
                        ("EpisodeSetup", "ApproachStorage", "SelectFrontier", "LookInside"),
                        ("ApproachStorage", "SelectFrontier", "LookInside"), "empty"),
    ANSWER_LOG: KeySpec(AnswerLog, "agent.eqa.answers.AnswerLog", ("EpisodeSetup", "QueryVLM"),
                        ("UpdatePredictionSet", "ShouldStop", "Answer", "AnswerFallback", "SelectFrontier",
                         "QueryDirections", "LookInside"), "empty"),
    PLAN: KeySpec((MovePlan, type(None)), "agent.planning.frontier_plan.MovePlan or None, the next move",
                  ("EpisodeSetup", "ApproachStorage", "SelectFrontier"), ("MarkExplorationComplete", "Navigate"), "None"),
    FRONTIER_GOAL: KeySpec((np.ndarray, type(None)), "numpy (x, y) of the frontier headed for, or None", ("EpisodeSetup", "SelectFrontier",
                           "Navigate"), ("SelectFrontier",), "None"),
    TRAJECTORY: KeySpec(list, "list[agent.pose.Pose2D], base poses along the route driven",
                        ("EpisodeSetup", "Navigate", "LookInside"), ("EpisodeSetup",), "[start pose]"),
    EXPLORATION_COMPLETE: KeySpec(bool, "bool, no reachable frontier is left", ("EpisodeSetup", "MarkExplorationComplete"),
                                  ("ShouldStop", "Answer", "AnswerFallback"), "False"),
    ANSWER: KeySpec(dict, "dict, written once when the episode answers", ("Answer", "AnswerFallback"), ("EpisodeRunner",), ""),
    SEMANTIC_MAP: KeySpec(SemanticMap, "agent.mapping.semantic_map.SemanticMap (semantic methods only)",
                          ("EpisodeSetup", "QueryDirections"), ("SelectFrontier",), "empty, at the method's default"),
    STOP_DECISION: KeySpec((StopDecision, type(None)), "agent.eqa.stopping.StopDecision or None", ("UpdatePredictionSet",),
                           ("CheckConfidence", "Answer", "AnswerFallback"), ""),
    PREDICTION_SET: KeySpec((list, type(None)), "list[str], the running conformal set (cp rule only, else None)",
                            ("UpdatePredictionSet",), ("EpisodeSetup",), ""),
    Q_HAT: KeySpec((float, type(None)), "float, the calibrated conformal threshold (cp rule only, else None)", ("UpdatePredictionSet",),
                   (), ""),
    EPSILON: KeySpec((float, type(None)), "float, the miscoverage the user accepts (cp rule only, else None)", ("UpdatePredictionSet",),
                     (), ""),
    ACTS: KeySpec(list, "list[behaviours.episode_state.ActRecord], every try to open storage and look inside",
                  ("EpisodeSetup", "LookInside"), ("ApproachStorage", "EpisodeSetup"), "[]"),
    APPROACH_STATE: KeySpec(ApproachState, "behaviours.episode_state.ApproachState", ("EpisodeSetup", "ApproachStorage"),
                            ("ApproachStorage",), "nothing seen yet"),
    LOOK_INSIDE_STATE: KeySpec(LookInsideState, "behaviours.episode_state.LookInsideState", ("EpisodeSetup", "LookInside"),
                               ("LookInside",), "nothing seen or tried yet"),
    FRONTIER_CHOICES: KeySpec(list, "list[behaviours.choices.FrontierChoice], the frontiers of the last choice",
                              ("EpisodeSetup", "SelectFrontier"), ("Recorder",), "[]"),
    DIRECTION_PROMPTS: KeySpec(list, "list[behaviours.choices.DirectionPrompt], the last prompt's points and LSV",
                               ("EpisodeSetup", "QueryDirections"), ("Recorder",), "[]"),
}


@dataclass(frozen=True)
class EpisodeStart:
    """What an episode's board is seeded from."""

    question: str
    choices: list[str]
    budget: int
    start_pose: Pose2D
    map_config: OccupancyConfig
    strategy: ExploreStrategy
    semantic_values: SemanticValueConfig


def seed_board(start: EpisodeStart, name: str = "EpisodeSetup") -> py_trees.blackboard.Client:
    """Put one episode's initial values on the (cleared) board.

    Args:
        start: the question, budget, start pose and settings of the episode.
        name: the client's name.

    Returns:
        The client that seeded the board, with WRITE access to what it seeded.
    """
    world_map = ExplorationMap(start.start_pose[:2], start.map_config)
    initial: dict[str, Any] = {
        QUESTION: start.question,
        CHOICES: list(start.choices),
        BUDGET: start.budget,
        MAP: world_map,
        ANSWER_LOG: AnswerLog(),
        TRAJECTORY: [start.start_pose],
        PLAN: None,
        FRONTIER_GOAL: None,
        EXPLORATION_COMPLETE: False,
        MAP_FIELDS: MapFields(),
        ACTS: [],
        APPROACH_STATE: ApproachState(),
        LOOK_INSIDE_STATE: LookInsideState(),
        FRONTIER_CHOICES: [],
        DIRECTION_PROMPTS: [],
    }
    if start.strategy.use_semantic:
        initial[SEMANTIC_MAP] = start.strategy.new_semantic_map(world_map.spec, start.semantic_values)
    writer = py_trees.blackboard.Client(name=name)
    for key, value in initial.items():
        writer.register_key(key, access=Access.WRITE)
        writer.set(key, value)
    return writer


def contract_problems(values: dict[str, Any], extra_keys: frozenset[str] = frozenset()) -> list[str]:
    """Where the values on a board break the contract.

    Args:
        values: key -> value, as `py_trees.blackboard.Blackboard.storage` holds them (keys with or
            without their leading "/").
        extra_keys: keys beyond the contract that may be there (those skills put into the tree
            by settings are bound to).

    Returns:
        One line per key the contract does not know, or whose value is not of its type.
    """
    problems = []
    for key, value in values.items():
        name = key.lstrip("/")
        spec = CONTRACT.get(name)
        if spec is None:
            if name not in extra_keys:
                problems.append(f"{name}: not in the EQA tree's contract")
        elif not isinstance(value, spec.type):
            problems.append(f"{name}: holds {type(value).__name__}, the contract says {spec.about}")
    return problems
