"""Settings and options no run could use are refused before any world starts, naming the key or the
option: every numeric setting has a range (agent.app.config_bounds), files that are not UTF-8 or not
TOML are named, and `homebot run` spawns no world for any of them."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
import typing
from pathlib import Path
from typing import Any

import pytest

from agent.app.cli import main
from agent.app.config import Config, ConfigError, load_config
from agent.app.config_bounds import BOUNDS, MAX_SEED, Locator, Range, check_bounds
from worlds.robot import CameraConfig

ROOT = Path(__file__).resolve().parent.parent


def _numeric_settings(config: Any, prefix: str = "") -> dict[str, Any]:
    """Dotted key -> default of every setting that is a number, or a tuple or table of numbers."""
    found: dict[str, Any] = {}
    hints = typing.get_type_hints(type(config))
    for f in dataclasses.fields(config):
        value, hint = getattr(config, f.name), hints[f.name]
        if dataclasses.is_dataclass(value):
            found.update(_numeric_settings(value, f"{prefix}{f.name}."))
            continue
        inner = typing.get_args(hint) if typing.get_origin(hint) in (tuple, dict) else (hint,)
        if any(t in (int, float) for t in inner):
            found[f"{prefix}{f.name}"] = value
    return found


def test_every_numeric_setting_has_a_range_its_default_lies_in() -> None:
    numeric = _numeric_settings(Config())
    assert len(numeric) > 90
    assert sorted(set(numeric) - set(BOUNDS)) == []
    assert sorted(set(BOUNDS) - set(numeric)) == ["bus.listen"]  # and nothing that is not a setting
    for key, default in numeric.items():
        check_bounds(key, default)
    check_bounds("bus.listen", Config().bus.listen)


def _outside(bound: Range) -> list[Any]:
    """Values just outside ``bound``, and the non-finite ones for a range of floats."""
    whole = isinstance(bound.low, int) and isinstance(bound.high, int)
    step = 1 if whole else 1e-3 * max(1.0, bound.high - bound.low)
    values = [bound.low if bound.low_open else bound.low - step, bound.high if bound.high_open else bound.high + step]
    return values if whole else [*values, math.nan, math.inf, -math.inf]


def _override(key: str, value: Any) -> tuple[str, str]:
    """(the ``--set`` item giving ``key`` the value ``value``, the name its refusal must start with)."""
    text = {math.nan: "NaN", math.inf: "Infinity", -math.inf: "-Infinity"}.get(value, repr(value))
    default = getattr(load_config(), key.split(".")[0])
    for part in key.split(".")[1:]:
        default = getattr(default, part)
    if isinstance(default, tuple):
        return f"{key}=[{', '.join([text] + [repr(v) for v in default[1:]])}]", f"{key}[0]"
    if isinstance(default, dict):
        first = next(iter(default))
        return f"{key}.{first}={text}", f"{key}.{first}"
    return f"{key}={text}", key


@pytest.mark.parametrize("key", sorted(k for k, b in BOUNDS.items() if isinstance(b, Range)))
def test_a_value_outside_its_range_or_not_finite_is_refused_naming_the_key(key: str) -> None:
    for value in _outside(BOUNDS[key]):
        item, name = _override(key, value)
        with pytest.raises(ConfigError) as refused:
            load_config(overrides=[item])
        assert str(refused.value).startswith(f"config: {name}: "), (item, str(refused.value))
        assert f"{BOUNDS[key]}" in str(refused.value)


@pytest.mark.parametrize("item, message", [
    ("map.resolution=0", "config: map.resolution: 0.0 must lie in (0, 10]"),
    ("bus.query_timeout_s=-1", "config: bus.query_timeout_s: -1.0 must lie in (0, 3600]"),
    ("bus.query_timeout_s=NaN", "config: bus.query_timeout_s: nan must be a finite number in (0, 3600]"),
    ("episode.budget=-5", "config: episode.budget: -5 must lie in [0, 100000]"),
    ("episode.tick_period_s=-0.5", "config: episode.tick_period_s: -0.5 must lie in [0, 60]"),
    ("camera.width=0", "config: camera.width: 0 must lie in [8, 4096]"),
    ("camera.hfov_deg=720", "config: camera.hfov_deg: 720.0 must lie in (10, 170)"),
    ('bus.listen=["bogus"]', "config: bus.listen[0]: endpoint 'bogus': expected a locator"),
    ("episode.budget=" + "9" * 5000, "config: episode.budget: expected int, got '99999"),
])
def test_the_reported_values_are_refused_naming_the_key(item: str, message: str) -> None:
    with pytest.raises(ConfigError) as refused:
        load_config(overrides=[item])
    assert str(refused.value).startswith(message)
    assert len(str(refused.value)) < 200


def test_the_edges_a_run_relies_on_are_allowed() -> None:
    config = load_config(overrides=["episode.tick_period_s=0", "episode.budget=0", "bus.listen=[]",
                                    "camera.width=8", "vlm.sim.seed=" + str(MAX_SEED)])
    assert (config.episode.tick_period_s, config.episode.budget, config.bus.listen) == (0.0, 0, ())


def test_the_camera_ranges_are_the_worlds() -> None:
    width, hfov = BOUNDS["camera.width"], BOUNDS["camera.hfov_deg"]
    assert isinstance(width, Range) and isinstance(hfov, Range)
    CameraConfig(width=width.low, height=width.high, hfov_deg=math.nextafter(hfov.low, 90.0))
    CameraConfig(hfov_deg=math.nextafter(hfov.high, 90.0))
    for refused in ({"width": width.low - 1}, {"height": width.high + 1}, {"hfov_deg": hfov.low},
                    {"hfov_deg": hfov.high}):
        with pytest.raises(ValueError):
            CameraConfig(**refused)


def test_the_largest_seed_is_the_worlds() -> None:
    from worlds.commands import MAX_SEED as WORLD_MAX_SEED

    assert MAX_SEED == WORLD_MAX_SEED


def test_a_listen_endpoint_is_checked_like_any_other() -> None:
    with pytest.raises(ValueError, match=r"^bus\.listen\[1\]: endpoint 'udp'"):
        Locator().check("bus.listen[1]", "udp")


@pytest.mark.parametrize("content, named", [
    (b'[camera]\nwidth = 320\nname = "\xff"\n', "not UTF-8 text (line 3, byte 29"),
    (b"[camera\nwidth = = 3\n", "not TOML"),
    (b"[episode]\nbudget = " + b"9" * 5000 + b"\n", "not TOML"),
    (b"x = " + b"[" * 100_000 + b"]" * 100_000 + b"\n", "nested too deeply"),
])
def test_a_config_file_that_is_not_utf8_toml_is_named(tmp_path: Path, content: bytes, named: str) -> None:
    path = tmp_path / "settings.toml"
    path.write_bytes(content)
    with pytest.raises(ConfigError) as refused:
        load_config(path)
    assert str(refused.value).startswith(f"config file {path}: ") and named in str(refused.value)
    assert len(str(refused.value)) < 300


def test_a_config_file_that_is_a_folder_is_named(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"config file .*: cannot be read"):
        load_config(tmp_path)


@pytest.mark.parametrize("options, named", [
    (["--seed", "-1"], "argument --seed: -1 is not a seed: seeds lie in 0..9223372036854775807"),
    (["--seed", "9" * 5000], "argument --seed: a whole number of 5000 digits is far too large"),
    (["--seed", "seven"], "argument --seed: 'seven' is not a whole number"),
    (["--connect", "bogus"], "argument --connect: endpoint 'bogus'"),
    (["--namespace", "bad ns"], "argument --namespace: namespace: 'bad ns'"),
])
def test_bad_run_options_are_refused_as_the_command_line_is_parsed(
        tmp_path: Path, capsys: pytest.CaptureFixture[str], options: list[str], named: str) -> None:
    with pytest.raises(SystemExit) as exited:
        main(["run", *options, "--out", str(tmp_path / "runs")])
    assert exited.value.code == 2
    assert named in capsys.readouterr().err
    assert not (tmp_path / "runs").exists()


@pytest.mark.parametrize("command", [["calibrate", "--suite", "s.jsonl", "--workers", "0"],
                                     ["eval", "explore", "--suite", "s.jsonl", "--limit", "-3"],
                                     ["eval", "coverage", "--homes", "0"],
                                     ["skill", "run", "open", "--timeout", "nan"],
                                     ["suite", "make", "--n", "0"]])
def test_counts_and_times_are_checked_on_every_command(command: list[str],
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exited:
        main(command)
    assert exited.value.code == 2
    error = capsys.readouterr().err
    assert "must be at least 1" in error or "must be a finite number of seconds above 0" in error


def test_a_missing_calibration_names_the_setting_in_process(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "--set", f"stop.calibration={tmp_path / 'none.json'}", "--out", str(tmp_path / "runs")]) == 2
    assert capsys.readouterr().err.startswith(f"homebot run: stop.calibration: {tmp_path / 'none.json'}: no such file")
    assert not (tmp_path / "runs").exists()


def _homebot(tmp_path: Path, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "agent.app.cli", *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=120)


@pytest.mark.parametrize("args, named", [
    (["--set", "map.resolution=0"], "homebot: config: map.resolution: 0.0 must lie in (0, 10]"),
    (["--set", "bus.query_timeout_s=NaN"], "homebot: config: bus.query_timeout_s: nan must be a finite number"),
    (["--set", "episode.budget=-5"], "homebot: config: episode.budget: -5 must lie in [0, 100000]"),
    (["--listen", "bogus"], "homebot: config: bus.listen[0]: endpoint 'bogus'"),
    (["--seed", "-1"], "argument --seed: -1 is not a seed"),
    (["--set", "stop.calibration=/nonexistent/calibration.json"],
     "homebot run: stop.calibration: /nonexistent/calibration.json: no such file"),
    (["--config", "NOT_UTF8"], "homebot: config file "),
])
def test_homebot_run_refuses_before_it_starts_a_world(tmp_path: Path, args: list[str], named: str) -> None:
    not_utf8 = tmp_path / "latin1.toml"
    not_utf8.write_bytes(b'[vlm]\nbackend = "sim\xe9"\n')
    out = tmp_path / "runs"
    done = _homebot(tmp_path, "run", *(str(not_utf8) if a == "NOT_UTF8" else a for a in args), "--out", str(out))
    assert done.returncode == 2, done.stderr
    assert named in done.stderr and "Traceback" not in done.stderr
    assert "starting a world" not in done.stdout
    assert not out.exists()  # no run folder, so no world.log: no world was spawned
