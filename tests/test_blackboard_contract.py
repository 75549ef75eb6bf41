"""The EQA tree's blackboard contract (behaviours/blackboard.py) is what the leaves really do: each
leaf registers only keys the contract names, with the access the contract gives it, and the
board an episode is seeded with holds what the contract says."""

from __future__ import annotations

import numpy as np
import py_trees
import pytest
from py_trees.common import Access

from agent.eqa.stopping import BudgetRule
from agent.mapping.occupancy import OccupancyConfig
from agent.mapping.semantic_map import SemanticValueConfig
from agent.planning.frontier_plan import ExploreConfig
from behaviours import blackboard as bb
from behaviours.eqa_tree import EqaTreeParts, build_eqa_tree


@pytest.fixture
def tree() -> py_trees.behaviour.Behaviour:
    """The EQA tree of the semantic method with the act branch: every leaf there is."""
    py_trees.blackboard.Blackboard.clear()
    yield build_eqa_tree(EqaTreeParts(link=None, vlm=None, explore=ExploreConfig(method="semantic"),  # type: ignore[arg-type]
                                      stopping=BudgetRule()))
    py_trees.blackboard.Blackboard.clear()


def _who(node: py_trees.behaviour.Behaviour, names: tuple[str, ...]) -> bool:
    return node.name in names or type(node).__name__ in names


def test_every_leaf_registers_only_contract_keys_with_the_access_the_contract_gives(tree) -> None:
    problems = []
    for node in tree.iterate():
        for client in node.blackboards:
            for key in client.read | client.write | client.exclusive:
                name = key.lstrip("/")
                spec = bb.CONTRACT.get(name)
                if spec is None:
                    problems.append(f"{node.name}: {name} is not in the contract")
                    continue
                writes = key in client.write or key in client.exclusive
                if writes and not _who(node, spec.writers):
                    problems.append(f"{node.name}: writes {name}, the contract's writers are {spec.writers}")
                if not writes and not _who(node, spec.readers + spec.writers):
                    problems.append(f"{node.name}: reads {name}, the contract's readers are {spec.readers}")
    assert problems == []


def test_every_leaf_the_contract_names_is_in_the_tree(tree) -> None:
    named = {name for spec in bb.CONTRACT.values() for name in spec.writers + spec.readers}
    present = {node.name for node in tree.iterate()} | {type(node).__name__ for node in tree.iterate()}
    assert named - present - {"EpisodeSetup", "EpisodeRunner", "Recorder"} == set()


def test_a_seeded_board_holds_what_the_contract_says() -> None:
    py_trees.blackboard.Blackboard.clear()
    try:
        bb.seed_board(bb.EpisodeStart("Where is the mug?", ["kitchen", "hall", "bedroom", "office"], 12,
                                      (1.0, 2.0, 0.0), OccupancyConfig(), ExploreConfig(method="semantic").strategy,
                                      SemanticValueConfig()))
        storage = py_trees.blackboard.Blackboard.storage
        assert bb.contract_problems(storage) == []
        assert {key.lstrip("/") for key in storage} == {key for key, spec in bb.CONTRACT.items() if spec.initial}
    finally:
        py_trees.blackboard.Blackboard.clear()


def test_a_value_of_the_wrong_type_or_an_unknown_key_is_named() -> None:
    problems = bb.contract_problems({"/budget": "12", "/frontier_goal": np.zeros(2), "/mine": 1},
                                    extra_keys=frozenset({"theirs"}))
    assert problems == ["budget: holds str, the contract says int, steps", "mine: not in the EQA tree's contract"]
    assert bb.contract_problems({"/theirs": 1}, extra_keys=frozenset({"theirs"})) == []
