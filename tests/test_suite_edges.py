"""Suite files that cannot be run as made are refused, naming the line or the scenario, before any
world starts: no scenarios, a line that is not an entry, two entries with one id, a home whose
checksum does not match. Only a torn last line after whole ones, an interrupted append, is dropped."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import pytest

from agent.app.cli import main
from agent.app.runtime.calibrations import SHIPPED_DIR
from worlds.suite import SuiteError, checked_entries, plan_split, read_suite, suite_entry, write_suite


@pytest.fixture(scope="module")
def lines(tmp_path_factory: pytest.TempPathFactory) -> list[str]:
    """The two lines of a real suite (seeds 0 and 1), ids suite-0000 and suite-0001."""
    path = write_suite(tmp_path_factory.mktemp("suite"), plan_split(2, [2], 0, ("suite",)))["suite"]
    return path.read_text(encoding="utf-8").splitlines()


def _suite(tmp_path: Path, text: str | bytes) -> Path:
    path = tmp_path / "suite.jsonl"
    if isinstance(text, bytes):
        path.write_bytes(text)
    else:
        path.write_text(text, encoding="utf-8")
    return path


def test_an_empty_suite_is_an_error(tmp_path: Path) -> None:
    for text in ("", "\n\n"):
        with pytest.raises(SuiteError, match=r"suite\.jsonl: holds no scenarios \(make a suite"):
            read_suite(_suite(tmp_path, text))


def test_a_suite_whose_only_line_is_not_json_is_an_error(tmp_path: Path, lines: list[str]) -> None:
    with pytest.raises(SuiteError, match=r"holds no scenarios: its only line is not JSON"):
        read_suite(_suite(tmp_path, lines[0][:40]))  # as if cut short: no line end
    with pytest.raises(SuiteError, match=r"suite\.jsonl:1: not valid JSON"):
        read_suite(_suite(tmp_path, "not json\n"))  # a whole line: no interrupted append wrote it


def test_a_torn_last_line_after_whole_ones_is_dropped_with_a_warning(
        tmp_path: Path, lines: list[str], caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, logger="worlds.suite"):
        entries = read_suite(_suite(tmp_path, lines[0] + "\n" + lines[1][:50]))
    assert [e["id"] for e in entries] == ["suite-0000"]
    assert "dropping a torn last line" in caplog.text


def test_a_bad_last_line_that_was_written_whole_is_an_error(tmp_path: Path, lines: list[str]) -> None:
    with pytest.raises(SuiteError, match=r"suite\.jsonl:2: not valid JSON"):
        read_suite(_suite(tmp_path, lines[0] + "\n" + lines[1][:50] + "\n"))


def test_blank_lines_are_skipped(tmp_path: Path, lines: list[str]) -> None:
    assert len(read_suite(_suite(tmp_path, lines[0] + "\n\n" + lines[1] + "\n\n"))) == 2


def test_duplicate_ids_are_refused_naming_the_id_and_both_lines(tmp_path: Path, lines: list[str]) -> None:
    twin = json.loads(lines[1])
    twin["id"] = "suite-0000"
    with pytest.raises(SuiteError, match=r"suite\.jsonl:2: scenario id 'suite-0000' is already used on line 1"):
        read_suite(_suite(tmp_path, lines[0] + "\n" + json.dumps(twin) + "\n"))


def test_a_wrong_home_checksum_is_refused_naming_the_scenario(tmp_path: Path, lines: list[str]) -> None:
    wrong = json.loads(lines[1])
    wrong["home_sha256"] = "0" * 64
    path = _suite(tmp_path, lines[0] + "\n" + json.dumps(wrong) + "\n")
    assert len(read_suite(path)) == 2  # the lines themselves are well formed
    assert [e["id"] for e in checked_entries(path, limit=1)] == ["suite-0000"]  # only what runs is checked
    for read in (lambda: checked_entries(path), lambda: suite_entry(path, "suite-0001")):
        with pytest.raises(SuiteError, match=r"scenario suite-0001: home_sha256 does not match the home seed 1"):
            read()
    assert suite_entry(path, "suite-0000")["seed"] == 0


@pytest.mark.parametrize("line", ['{"seed": ' + "9" * 5000 + "}", "[" * 100_000 + "]" * 100_000,
                                  '{"format": "homebot-suite", "version": 1}'])
def test_a_line_no_suite_holds_is_named_without_a_traceback(tmp_path: Path, lines: list[str], line: str) -> None:
    with pytest.raises(SuiteError, match=r"suite\.jsonl:2: "):
        read_suite(_suite(tmp_path, lines[0] + "\n" + line + "\n" + lines[1] + "\n"))


def test_a_suite_that_is_not_utf8_is_named(tmp_path: Path, lines: list[str]) -> None:
    with pytest.raises(SuiteError, match=r"suite\.jsonl:2: not UTF-8 text"):
        read_suite(_suite(tmp_path, lines[0].encode() + b"\n\xff\n"))


def test_suite_make_resumes_a_file_left_empty_or_with_its_only_line_torn(tmp_path: Path, lines: list[str]) -> None:
    for text in ("", lines[0][:30]):
        path = _suite(tmp_path, text)
        write_suite(tmp_path, plan_split(2, [2], 0, ("suite",)))
        assert path.read_text(encoding="utf-8").splitlines() == lines


@pytest.mark.parametrize("command", [["calibrate", "--out", "OUT/calibration.json"],
                                     ["eval", "explore", "--out", "OUT"], ["eval", "stop", "--out", "OUT"]])
def test_suite_commands_refuse_a_suite_before_any_world_starts(
        tmp_path: Path, lines: list[str], capsys: pytest.CaptureFixture[str], command: list[str]) -> None:
    out = tmp_path / "out"
    wrong = json.loads(lines[0])
    wrong["home_sha256"] = "f" * 64
    cases = {"": "holds no scenarios", lines[0][:40]: "its only line is not JSON",
             json.dumps(wrong) + "\n": "scenario suite-0000: home_sha256 does not match",
             lines[0] + "\n" + lines[0] + "\n": "scenario id 'suite-0000' is already used on line 1"}
    for text, named in cases.items():
        path = _suite(tmp_path, text)
        args = [a.replace("OUT", str(out)) for a in command] + ["--suite", str(path), "--workers", "1"]
        assert main(args + (["--calibration", str(SHIPPED_DIR / "calibration-semantic-sim.json")]
                            if command[1:2] == ["stop"] else [])) == 2
        error = capsys.readouterr().err
        assert named in error and "Traceback" not in error
        assert not any(out.rglob("*.jsonl"))  # no episode ran, none was recorded


def test_run_refuses_a_scenario_whose_home_does_not_match(tmp_path: Path, lines: list[str],
                                                          capsys: pytest.CaptureFixture[str]) -> None:
    wrong = json.loads(lines[1])
    wrong["home_sha256"] = "0" * 64
    path = _suite(tmp_path, lines[0] + "\n" + json.dumps(wrong) + "\n")
    out = tmp_path / "runs"
    assert main(["run", "--suite", str(path), "--scenario", "suite-0001", "--out", str(out)]) == 2
    assert "scenario suite-0001: home_sha256 does not match" in capsys.readouterr().err
    assert not out.exists()
