"""`homebot run`'s shortcut options reach the configuration they stand for; `--suite` and
`--scenario` run one scenario of a suite."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from worlds.bus.session import free_tcp_endpoint
from agent.app.cli import build_parser, main
from agent.app.cli.run import shortcut_overrides
from agent.app.config import load_config
from worlds.suite import plan_split, read_suite, write_suite


def test_method_stop_and_epsilon_become_settings() -> None:
    args = build_parser().parse_args(["run", "--method", "lfe", "--stop", "budget", "--epsilon", "0.2"])
    overrides = shortcut_overrides(args)
    assert overrides == ["explore.method=lfe", "stop.rule=budget", "stop.epsilon=0.2"]
    config = load_config(None, overrides)
    assert (config.explore.method, config.stop.rule, config.stop.epsilon) == ("lfe", "budget", 0.2)


def test_options_left_out_change_nothing() -> None:
    assert shortcut_overrides(build_parser().parse_args(["run"])) == []


def test_an_unknown_stopping_rule_is_refused_at_the_command_line(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit):
        build_parser().parse_args(["run", "--stop", "never"])
    assert "invalid choice: 'never'" in capsys.readouterr().err


@pytest.fixture(scope="module")
def hidden_suite(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A suite of two hidden-evidence scenarios (seeds 60 and 61)."""
    out = tmp_path_factory.mktemp("suite")
    return write_suite(out, plan_split(2, [2], 60, ("hidden",)), hidden=True)["hidden"]


def test_an_unknown_scenario_id_names_how_many_the_suite_holds(hidden_suite: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--suite", str(hidden_suite), "--scenario", "hidden-0099"]) == 2
    error = capsys.readouterr().err
    assert "'hidden-0099'" in error and "holds 2 scenarios" in error and "hidden-0000, hidden-0001" in error


@pytest.mark.parametrize("options, named", [
    (["--suite", "SUITE"], "--suite and --scenario go together"),
    (["--scenario", "hidden-0000"], "--suite and --scenario go together"),
    (["--suite", "SUITE", "--scenario", "hidden-0000", "--seed", "3"], "--seed: cannot be combined with --suite"),
    (["--suite", "missing.jsonl", "--scenario", "hidden-0000"], "--suite: [Errno 2]"),
])
def test_suite_options_that_do_not_fit_are_refused_before_any_world_starts(
        hidden_suite: Path, capsys: pytest.CaptureFixture[str], options: list[str], named: str) -> None:
    assert main(["run", *(str(hidden_suite) if o == "SUITE" else o for o in options)]) == 2
    assert named in capsys.readouterr().err


@pytest.mark.slow
def test_run_runs_the_suite_scenario_named_in_its_home(hidden_suite: Path, tmp_path: Path) -> None:
    entry = read_suite(hidden_suite)[1]
    done = subprocess.run(
        [sys.executable, "-m", "agent.app.cli", "run", "--suite", str(hidden_suite), "--scenario", entry["id"],
         "--set", "episode.budget=1", "--stop", "budget", "--listen", free_tcp_endpoint(), "--out", str(tmp_path)],
        capture_output=True, text=True, timeout=600,
    )
    assert done.returncode == 0, done.stderr
    assert f"{entry['id']} (seed {entry['seed']})" in done.stdout
    [result_file] = tmp_path.glob("*/result.json")
    result = json.loads(result_file.read_text())
    assert result["seed"] == entry["seed"]
    assert (result["question"], result["choices"]) == (entry["scenario"]["question"], entry["scenario"]["choices"])
    assert result["evaluation"]["target"]["kind"] == "storage"
    assert result["startup_s"] > 0  # from the process's start to the first observation on the board
    assert f"first observation {result['startup_s']:.1f} s after `homebot run` started" in done.stdout
