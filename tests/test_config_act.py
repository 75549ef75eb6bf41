"""The act branch's settings, ``act.*``: loaded from TOML and ``--set``, handed to the behaviours
that use them, and a bad value refused with its dotted name before any world starts."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import py_trees
import pytest

import agent.app.runtime.run as runtime
from agent.app.cli import build_parser, main
from agent.app.cli.options import load_settings
from agent.app.config import ConfigError, load_config
from agent.eqa.stopping import BudgetRule
from behaviours.approach_storage import ApproachConfig, ApproachStorage
from behaviours.eqa_tree import EqaTreeParts, build_eqa_tree
from behaviours.look_inside import LookInside, LookInsideConfig
from skills.arm.stand import StandConfig


class _TreeBuilt(Exception):
    """Stops an episode once the tree's parts are made, before any world is needed."""


def _tree_of(config: Any, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> py_trees.behaviour.Behaviour:
    """The EQA tree an episode under ``config`` builds (the runtime's own parts, without a world)."""
    made: list[EqaTreeParts] = []

    def capture(*args: Any, **kwargs: Any) -> EqaTreeParts:
        made.append(EqaTreeParts(*args, **kwargs))
        raise _TreeBuilt

    monkeypatch.setattr(runtime, "EqaTreeParts", capture)
    scenario = {"question": "Is there a towel in the cabinet?", "choices": ["yes", "no"], "budget": 3, "seed": 0}
    try:
        with pytest.raises(_TreeBuilt):
            runtime._run_tree("act-settings", scenario, {"base_pose": [0.0, 0.0, 0.0]}, config, None, BudgetRule(),
                              None, None, None, tmp_path, None, [], [])
        return build_eqa_tree(made[0])
    finally:
        py_trees.blackboard.Blackboard.clear()


def test_the_defaults_are_the_behaviours_own() -> None:
    act = load_config().act
    assert act == LookInsideConfig()
    assert act.approach == ApproachConfig() and act.stand == StandConfig()


def test_set_on_the_command_line_reaches_approach_storage_and_look_inside(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    args = build_parser().parse_args(["run", "--set", "act.approach.views=3", "--set", "act.max_parts=2",
                                      "--set", "act.min_look.drawer=0.08", "--set", "explore.method=fbe"])
    tree = _tree_of(load_settings(args), tmp_path, monkeypatch)
    [approach] = [node for node in tree.iterate() if isinstance(node, ApproachStorage)]
    [look] = [node for node in tree.iterate() if isinstance(node, LookInside)]
    assert approach.config == ApproachConfig(views=3)
    assert look.config.max_parts == 2 and look.config.approach.views == 3
    assert look.config.min_look == {**LookInsideConfig().min_look, "drawer": 0.08}


def test_a_toml_file_sets_them_too(tmp_path: Path) -> None:
    path = tmp_path / "act.toml"
    path.write_text("[act]\nreach_m = 3.5\n[act.approach]\nsqueeze_m = 0.05\n[act.stand]\nmax_plans = 4\n")
    act = load_config(path).act
    assert (act.reach_m, act.approach.squeeze_m, act.stand.max_plans) == (3.5, 0.05, 4)


@pytest.mark.parametrize("override, message", [
    ("act.approach.views=0", "config: act.approach.views: 0 must lie in [1, 100]"),
    ("act.approach.views=many", "config: act.approach.views: expected int, got 'many'"),
    ("act.approach.squeeze_m=0.5", "config: act.approach.squeeze_m: 0.5 must lie in [0, 0.15]"),
    ("act.approach.viewpoint.bearings=0", "config: act.approach.viewpoint.bearings: 0 must lie in [1, 360]"),
    ("act.approach.sightings.min_pixels=0", "config: act.approach.sightings.min_pixels: 0 must lie in [1, 10000000]"),
    ("act.approach.fast=1", "config: unknown key act.approach.fast (known here: done_m"),
    ("act.min_look.door=wide", "config: act.min_look.door: expected number, got 'wide'"),
    ("act.min_look.window=0.1", "config: act.min_look: {"),
    ("act.stand.max_plans=0", "config: act.stand.max_plans: 0 must lie in [1, 1000]"),
])
def test_a_bad_value_is_refused_naming_its_key(override: str, message: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(ConfigError) as refused:
        load_config(None, [override])
    assert str(refused.value).startswith(message)
    assert main(["run", "--set", override]) == 2
    assert capsys.readouterr().err.startswith(f"homebot: {message}")
