"""`homebot run`'s shortcut options reach the configuration they stand for."""

from __future__ import annotations

import pytest

from agent.cli import _parser, shortcut_overrides
from agent.config import load_config


def test_method_stop_and_epsilon_become_settings() -> None:
    args = _parser().parse_args(["run", "--method", "lfe", "--stop", "budget", "--epsilon", "0.2"])
    overrides = shortcut_overrides(args)
    assert overrides == ["explore.method=lfe", "stop.rule=budget", "stop.epsilon=0.2"]
    config = load_config(None, overrides)
    assert (config.explore.method, config.stop.rule, config.stop.epsilon) == ("lfe", "budget", 0.2)


def test_options_left_out_change_nothing() -> None:
    assert shortcut_overrides(_parser().parse_args(["run"])) == []


def test_an_unknown_stopping_rule_is_refused_at_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        _parser().parse_args(["run", "--stop", "never"])
    assert "invalid choice: 'never'" in capsys.readouterr().err
