"""The calibration file: round trip, checksum and format checks, and refusing a mismatched policy."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path

import pytest

from agent.app.config import Config, load_config
from agent.eqa.answers import StepScores
from agent.eqa.calibration import (
    CALIBRATION_FORMAT,
    CALIBRATION_VERSION,
    Calibration,
    CalibrationEpisode,
    CalibrationError,
    read_calibration,
)
from agent.app.runtime.calibrations import calibration_for, made_with, mismatches, write_calibration
from agent.eqa.conformal import conformal_quantile, nonconformity


def step(t: int, a: float, b: float, c: float, d: float, rel: float) -> dict:
    return {"step": t, "answer_probs": {"A": a, "B": b, "C": c, "D": d}, "relevance": rel}


def sample_calibration(config: Config | None = None) -> Calibration:
    episodes = [
        CalibrationEpisode("home-1/q0", 11, "A", [step(1, 0.4, 0.3, 0.2, 0.1, 0.5), step(2, 0.7, 0.1, 0.1, 0.1, 0.9)]),
        CalibrationEpisode("home-1/q1", 12, "B", [step(1, 0.25, 0.25, 0.25, 0.25, 0.3)]),
        CalibrationEpisode("home-2/q0", 13, "C", [step(1, 0.1, 0.1, 0.1, 0.7, 0.8), step(2, 0.05, 0.05, 0.85, 0.05, 1.0),
                                                  step(3, 0.3, 0.3, 0.2, 0.2, 0.6)]),
        CalibrationEpisode("home-2/q1", 14, "D", [step(1, 0.0, 0.0, 0.1, 0.9, 0.95)]),
        CalibrationEpisode("home-3/q0", 15, "A", [step(1, 0.123456789, 0.3, 0.376543211, 0.2, 0.333333333)]),
    ]
    suite = {"file": "calib.jsonl", "sha256": "0" * 64, "entries": 6}
    return Calibration(made_with(config or Config()), suite, episodes, failed=["home-3/q1"], created="2024-06-01T12:00:00")


DEFAULT_METHOD = Config().explore.method
OTHER_METHOD = "fbe" if DEFAULT_METHOD != "fbe" else "semantic"


def with_relevance(text: str, old: str, new: str) -> str:
    """``text`` with the one relevance ``old`` replaced by ``new``, however the JSON is spaced."""
    pattern = re.compile(r'("relevance":\s*)' + re.escape(old) + r"\b")
    assert len(pattern.findall(text)) == 1
    return pattern.sub(lambda m: m.group(1) + new, text)


def written(tmp_path: Path, calibration: Calibration | None = None, name: str = "calibration.json") -> Path:
    path = tmp_path / name
    write_calibration(path, calibration or sample_calibration())
    return path


# ---------------------------------------------------------------------------------------------
# round trip


def test_round_trip_keeps_scores_quantile_and_provenance(tmp_path: Path) -> None:
    original = sample_calibration()
    path = written(tmp_path, original)
    loaded = read_calibration(path)
    assert loaded.kappas == original.kappas
    assert loaded.made_with == original.made_with == made_with(Config())
    assert loaded.suite == original.suite
    assert loaded.failed == ["home-3/q1"]
    assert loaded.created == "2024-06-01T12:00:00"
    assert [e.id for e in loaded.episodes] == [e.id for e in original.episodes]
    assert [(e.seed, e.ground_truth) for e in loaded.episodes] == [(11, "A"), (12, "B"), (13, "C"), (14, "D"), (15, "A")]
    for eps in (0.2, 0.3, 0.5, 0.7):
        assert loaded.q_hat(eps) == original.q_hat(eps) == conformal_quantile(original.kappas, eps)
    assert loaded.q_hat(0.1) == math.inf  # five scores cannot promise 90 %
    assert mismatches(loaded.made_with, Config()) == []
    assert not list(tmp_path.glob("*.tmp"))  # written atomically, nothing left behind


def test_kappas_are_the_episodes_nonconformity(tmp_path: Path) -> None:
    loaded = read_calibration(written(tmp_path))
    first = loaded.episodes[0]
    steps = [StepScores(s["step"], s["answer_probs"], s["relevance"]) for s in first.step_scores]
    assert first.kappa == nonconformity(steps, "A") == pytest.approx(1 + 0.5 * 0.6)
    data = json.loads((tmp_path / "calibration.json").read_text())
    assert data["format"] == CALIBRATION_FORMAT and data["version"] == CALIBRATION_VERSION
    assert data["n"] == 5
    assert [e["kappa"] for e in data["episodes"]] == [round(k, 6) for k in loaded.kappas]
    assert data["checksum"].startswith("sha256:")


def test_reformatting_the_json_keeps_the_checksum_valid(tmp_path: Path) -> None:
    path = written(tmp_path)
    data = json.loads(path.read_text())
    path.write_text(json.dumps(dict(reversed(list(data.items()))), separators=(",", ":")))
    assert read_calibration(path).kappas == sample_calibration().kappas


# ---------------------------------------------------------------------------------------------
# refused files


@pytest.mark.parametrize("edit", ["relevance", "probability", "kappa", "truth", "made_with", "drop_episode"])
def test_an_edited_file_fails_its_checksum(tmp_path: Path, edit: str) -> None:
    path = written(tmp_path)
    data = json.loads(path.read_text())
    episode = data["episodes"][1]
    if edit == "relevance":
        episode["step_scores"][0]["relevance"] = 0.4  # was 0.3
    elif edit == "probability":
        episode["step_scores"][0]["answer_probs"]["B"] = 0.35  # was 0.25
    elif edit == "kappa":
        episode["kappa"] = round(episode["kappa"] + 1e-6, 6)
    elif edit == "truth":
        episode["ground_truth"] = "A"
    elif edit == "made_with":
        data["made_with"]["explore"]["method"] = OTHER_METHOD
    else:
        del data["episodes"][1]
    path.write_text(json.dumps(data, indent=2))
    with pytest.raises(CalibrationError, match="checksum") as caught:
        read_calibration(path)
    assert str(path) in str(caught.value)


def test_a_changed_byte_in_a_score_fails_its_checksum(tmp_path: Path) -> None:
    path = written(tmp_path)
    path.write_text(with_relevance(path.read_text(), "0.95", "0.96"))
    with pytest.raises(CalibrationError, match="checksum"):
        read_calibration(path)


def test_missing_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "nowhere.json"
    with pytest.raises(CalibrationError, match="not found") as caught:
        read_calibration(path)
    assert str(path) in str(caught.value)


@pytest.mark.parametrize(
    ("content", "words"),
    [
        ("this is not json {", "JSON"),
        ('{"format": "homebot-calibration", "version": 1,', "JSON"),  # cut short
        ("", "JSON"),
        ("[1, 2, 3]", "not a homebot-calibration file"),
        ('{"format": "something-else", "version": 1}', "not a homebot-calibration file"),
        ('{"version": 1}', "not a homebot-calibration file"),
        ('{"format": "homebot-calibration", "version": 2}', "version 2"),
        ('{"format": "homebot-calibration"}', "version None"),
    ],
)
def test_unreadable_or_foreign_files_are_named(tmp_path: Path, content: str, words: str) -> None:
    path = tmp_path / "odd.json"
    path.write_text(content)
    with pytest.raises(CalibrationError, match=words) as caught:
        read_calibration(path)
    assert str(path) in str(caught.value)


def test_a_directory_is_not_a_calibration_file(tmp_path: Path) -> None:
    with pytest.raises(CalibrationError) as caught:
        read_calibration(tmp_path)
    assert str(tmp_path) in str(caught.value)


def test_a_binary_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "binary.json"
    path.write_bytes(b"\xff\xfe\x00\x01garbage")
    with pytest.raises(CalibrationError) as caught:
        read_calibration(path)
    assert str(path) in str(caught.value)


def test_a_file_with_no_episode_is_refused(tmp_path: Path) -> None:
    empty = Calibration(made_with(Config()), {"file": "s.jsonl"}, [], failed=["a", "b"], created="x")
    path = written(tmp_path, empty)
    with pytest.raises(CalibrationError, match="no episode") as caught:
        read_calibration(path)
    assert str(path) in str(caught.value)


# ---------------------------------------------------------------------------------------------
# mismatches


def test_a_different_exploration_method_is_a_mismatch() -> None:
    calibration = sample_calibration(Config())
    found = mismatches(calibration.made_with, load_config(overrides=[f"explore.method={OTHER_METHOD}"]))
    assert len(found) == 1
    assert found[0].startswith("explore.method:")
    assert f"calibrated with {DEFAULT_METHOD!r}, this run uses {OTHER_METHOD!r}" in found[0]


def test_mismatches_list_every_differing_key_in_order() -> None:
    calibration = sample_calibration(Config())
    config = load_config(overrides=[f"explore.method={OTHER_METHOD}", "vlm.sim.skill=0.5", "map.floor_band=[-0.1, 0.1]"])
    keys = [line.split(":")[0] for line in mismatches(calibration.made_with, config)]
    assert keys == ["explore.method", "map.floor_band", "vlm.sim.skill"]


def test_settings_that_do_not_change_the_answers_are_not_mismatches() -> None:
    calibration = sample_calibration(Config())
    assert Config().vlm.backend == "sim"
    quiet = load_config(overrides=["vlm.openai.timeout_s=99", "vlm.openai.retries=5", "episode.max_seconds=10",
                                   "bus.query_timeout_s=3", "stop.epsilon=0.1", "stop.rule=entropy",
                                   "episode.budget=12"])  # fewer steps keep the guarantee (docs/stopping.md)
    assert mismatches(calibration.made_with, quiet) == []


def test_a_different_vlm_backend_is_a_mismatch() -> None:
    calibration = sample_calibration(Config())
    found = mismatches(calibration.made_with, load_config(overrides=["vlm.backend=openai", "vlm.openai.model=qwen"]))
    keys = {line.split(":")[0] for line in found}
    # the sim settings the file had and the openai ones the run has are each one difference
    assert keys == {"vlm.backend", "vlm.openai", "vlm.sim"}
    assert any("this run uses {'model': 'qwen'}" in line for line in found)


# ---------------------------------------------------------------------------------------------
# calibration_for


def test_calibration_for_refuses_another_policy_and_says_how_to_go_on(tmp_path: Path) -> None:
    path = written(tmp_path, sample_calibration(load_config(overrides=[f"explore.method={OTHER_METHOD}"])))
    config = load_config(overrides=[f"stop.calibration={path}"])
    with pytest.raises(CalibrationError) as caught:
        calibration_for(config)
    text = str(caught.value)
    assert str(path) in text
    assert "explore.method" in text
    assert "stop.accept_mismatched_calibration" in text
    accepted = load_config(overrides=[f"stop.calibration={path}", "stop.accept_mismatched_calibration=true"])
    calibration, used = calibration_for(accepted)
    assert used == path
    assert calibration.kappas == sample_calibration().kappas
    assert calibration.made_with["explore"]["method"] == OTHER_METHOD


def test_calibration_for_a_matching_policy(tmp_path: Path) -> None:
    path = written(tmp_path, sample_calibration(load_config(overrides=[f"explore.method={OTHER_METHOD}"])))
    config = load_config(overrides=[f"stop.calibration={path}", f"explore.method={OTHER_METHOD}", "vlm.openai.timeout_s=5"])
    calibration, used = calibration_for(config)
    assert used == path and len(calibration.episodes) == 5


def test_calibration_for_passes_on_a_damaged_file(tmp_path: Path) -> None:
    path = written(tmp_path)
    path.write_text(with_relevance(path.read_text(), "0.95", "0.5"))
    config = load_config(overrides=[f"stop.calibration={path}", "stop.accept_mismatched_calibration=true"])
    with pytest.raises(CalibrationError, match="checksum"):
        calibration_for(config)


@pytest.mark.parametrize("bad_step, problem", [
    (step(1, 0.0, 1.0, 0.0, 0.0, 1.5), "outside [1, 2]"),  # Rel above 1
    ({"step": 1, "answer_probs": {"B": 1.0}, "relevance": 0.5}, "malformed"),  # the truth A is not scored
])
def test_an_episode_that_gives_no_valid_score_is_named_on_load(tmp_path: Path, bad_step: dict, problem: str) -> None:
    from agent.eqa.calibration import _checksum

    data = sample_calibration().to_json()
    data["episodes"].append({"id": "bad", "seed": 1, "ground_truth": "A", "kappa": 1.0, "step_scores": [bad_step]})
    body = {key: value for key, value in data.items() if key != "checksum"}
    path = tmp_path / "calibration.json"
    path.write_text(json.dumps({**body, "checksum": _checksum(body)}))
    with pytest.raises(CalibrationError, match=re.escape(problem)) as raised:
        read_calibration(path)
    assert str(path) in str(raised.value)
