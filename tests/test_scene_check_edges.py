"""`homebot scene check` answers a file no spec parser should choke on with the field at fault and
exit 1, never a traceback: nesting far too deep, integers of thousands of digits, a list at the top."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from worlds.home import generate_home
from worlds.scene_cli import main
from worlds.spec import dump_spec

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def spec_text() -> str:
    """A valid spec (seed 3's home) as JSON text."""
    return json.dumps(dump_spec(generate_home(3)))


def _check(tmp_path: Path, text: str, capsys: pytest.CaptureFixture[str]) -> list[str]:
    """Run `scene check` on ``text``; it must fail with exit 1; the problems' lines."""
    path = tmp_path / "scene.json"
    path.write_text(text, encoding="utf-8")
    assert main(["check", str(path)]) == 1
    error = capsys.readouterr().err.splitlines()
    assert error[0].startswith(f"{path}: invalid scene spec (")
    return [line.strip() for line in error[1:]]


@pytest.mark.parametrize("depth", [100_000, 5_000])
def test_deep_nesting_is_named(tmp_path: Path, capsys: pytest.CaptureFixture[str], depth: int) -> None:
    problems = _check(tmp_path, '{"rooms": ' + "[" * depth + "]" * depth + "}", capsys)
    assert problems == [f"{tmp_path / 'scene.json'}: nested too deeply for a scene spec (a spec nests a few levels)"]


def test_an_integer_of_thousands_of_digits_is_named_by_its_field(tmp_path: Path, spec_text: str,
                                                                  capsys: pytest.CaptureFixture[str]) -> None:
    problems = _check(tmp_path, spec_text.replace('"seed": 3', '"seed": ' + "9" * 5000, 1), capsys)
    assert len(problems) == 1 and problems[0].startswith("seed: ") and len(problems[0]) < 200


def test_a_coordinate_of_hundreds_of_digits_is_named_by_its_field(tmp_path: Path, spec_text: str,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    spec = json.loads(spec_text)
    spec["rooms"][0]["rect"][2] = int("9" * 400)
    problems = _check(tmp_path, json.dumps(spec), capsys)
    assert problems and all(p.startswith("rooms[0].rect[2]: ") for p in problems)


def test_a_top_level_array_names_the_spec(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert _check(tmp_path, "[1, 2]", capsys) == ["spec: expected an object, got list"]


def test_one_problem_is_one_problem(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "scene.json"
    path.write_text("[]", encoding="utf-8")
    assert main(["check", str(path)]) == 1
    assert capsys.readouterr().err.startswith(f"{path}: invalid scene spec (1 problem)\n")


def test_the_real_command_exits_1_without_a_traceback(tmp_path: Path) -> None:
    path = tmp_path / "deep.json"
    path.write_text("[" * 100_000 + "]" * 100_000, encoding="utf-8")
    done = subprocess.run([sys.executable, "-m", "agent.app.cli", "scene", "check", str(path)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 1
    assert "nested too deeply" in done.stderr and "Traceback" not in done.stderr
