"""Rerun recordings: a real episode's recording.rrd read back with Rerun's own reader, `homebot replay`
refusing a folder without one, and evaluations keeping recordings only when asked."""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path
from typing import Any

import py_trees
import pytest
from rerun.chunk import RrdReader

from agent.app.cli import build_parser, main
from agent.app.config import load_config
from agent.app.runtime import recording_log as view
from agent.app.runtime.run import RunRequest, run_episode
from agent.app.runtime.viewer import RECORDING_FILE
from behaviours import blackboard as bb
from worlds.bus.session import free_tcp_endpoint

pytestmark = pytest.mark.slow


def _rows(path: Path) -> dict[str, list[dict[str, Any]]]:
    """Entity path (without the leading /) -> its logged rows (time columns and components), in
    tick order; static rows are left out."""
    rows: dict[str, list[dict[str, Any]]] = defaultdict(list)
    for chunk in RrdReader(path).stream():
        if chunk.is_static:
            continue
        data = chunk.to_record_batch().to_pydict()
        for i in range(chunk.num_rows):
            rows[chunk.entity_path.lstrip("/")].append({name: column[i] for name, column in data.items()})
    return {entity: sorted(found, key=lambda row: row.get("tick", 0)) for entity, found in rows.items()}


class _Observations:
    """Counts the distinct observations the board held after each tick (a snapshot sink)."""

    def __init__(self) -> None:
        self.seen: list[Any] = []

    def __call__(self, _snapshot: dict[str, Any]) -> None:
        observation = py_trees.blackboard.Blackboard.storage.get("/" + bb.OBSERVATION)
        if observation is not None and not any(observation is seen for seen in self.seen):
            self.seen.append(observation)


def test_an_episode_records_each_observation_step_and_status_change(tmp_path: Path) -> None:
    config = load_config(overrides=[f'bus.listen=["{free_tcp_endpoint()}"]', "episode.budget=3", "stop.rule=budget"])
    observations = _Observations()
    result = run_episode(RunRequest(seed=3, config=config, out_root=tmp_path, save_map=False),
                         extra_sinks=[observations])
    assert result["status"] == "answered", result["reason"]
    rows = _rows(Path(result["folder"]) / RECORDING_FILE)

    frames = len(observations.seen)
    assert frames >= result["steps"] == 3
    for entity in (view.CAMERA, view.RGB, view.DEPTH, view.SEGMENTATION):
        assert len(rows[entity]) == frames, entity
    assert rows[view.CAMERA][0]["Pinhole:image_from_camera"] is not None
    labels = rows[view.SEGMENTATION][0]["AnnotationContext:context"][0]
    assert labels and all(entry["class_description"]["info"]["label"] for entry in labels)
    for letter in "ABCD":
        assert [row["step"] for row in rows[f"{view.ANSWERS}/{letter}"]] == [1, 2, 3]
    scores = result["step_scores"]
    assert [row["Scalars:scalars"][0] for row in rows[view.RELEVANCE]] == pytest.approx(
        [step["relevance"] for step in scores], abs=1e-5)
    assert [row["Scalars:scalars"][0] for row in rows[f"{view.ANSWERS}/A"]] == pytest.approx(
        [step["answer_probs"]["A"] for step in scores], abs=1e-5)
    for layer in view.MAP_LAYERS:
        assert 1 <= len(rows[f"map/{layer}"]) <= result["ticks"]
    assert rows[view.MAP_TRAJECTORY] and rows[view.WORLD_TRAJECTORY] and rows[view.PLAN_PATH]
    statuses = [row["TextLog:text"][0] for row in rows[view.TREE_STATUS_TEXT]]
    assert statuses[0] == "RUNNING" and statuses[-1] == "SUCCESS"
    assert all(a != b for a, b in zip(statuses, statuses[1:])), "a status is logged only when it changes"
    assert len(rows[view.TREE_STATUS]) == len(statuses) < result["ticks"]


def test_replay_of_a_folder_without_a_recording_names_the_path(tmp_path: Path,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["replay", str(tmp_path)]) == 2
    assert str(tmp_path / RECORDING_FILE) in capsys.readouterr().err
    (tmp_path / RECORDING_FILE).write_text("not a recording")
    assert main(["replay", str(tmp_path)]) == 2
    assert "not a Rerun recording" in capsys.readouterr().err


def test_evaluations_record_only_when_asked(tmp_path: Path) -> None:
    parser = build_parser()
    assert parser.parse_args(["run", "--viewer"]).viewer
    assert not parser.parse_args(["run"]).viewer
    for command in (["eval", "explore", "--suite", "s.jsonl"], ["eval", "stop", "--suite", "s.jsonl",
                                                                 "--calibration", "c.json"], ["eval", "interactive"]):
        assert not parser.parse_args(command).record
        assert parser.parse_args([*command, "--record"]).record

    out = tmp_path / "interactive"
    assert main(["eval", "interactive", "--tasks", "drawer-only", "--variants", "1", "--out", str(out)]) == 0
    assert not (out / "recordings").exists()
    assert main(["eval", "interactive", "--tasks", "door-only", "--variants", "1", "--out", str(out),
                 "--record"]) == 0
    rows = _rows(out / "recordings" / "door-only-0-symbolic" / RECORDING_FILE)
    graph = rows["acsg"][0]
    assert len(graph["GraphNodes:node_ids"]) >= 2 and graph["GraphEdges:edges"]
