"""Rerun recordings: a real episode's recording.rrd read back with Rerun's own reader (the frames,
scores, map, frontiers weighed and prompt points among them), `homebot replay` refusing a folder
without one, evaluations keeping recordings only when asked, and a robot tabletop scene's recording
holding the arm's joints after each skill run."""

from __future__ import annotations

import json
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
from worlds.home import generate_home
from worlds.scenario import make_scenario

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


class _Distinct:
    """Keeps the distinct objects the board held under ``key`` after each tick (a snapshot sink)."""

    def __init__(self, key: str) -> None:
        self.key = key
        self.seen: list[Any] = []

    def __call__(self, _snapshot: dict[str, Any]) -> None:
        value = py_trees.blackboard.Blackboard.storage.get("/" + self.key)
        if value is not None and not any(value is seen for seen in self.seen):
            self.seen.append(value)


def _drawn(rows: list[dict[str, Any]], kind: str) -> list[dict[str, Any]]:
    """The rows that drew points of ``kind`` (Points2D, Points3D), not those that cleared them."""
    return [row for row in rows if row.get(f"{kind}:positions")]


def test_an_episode_records_each_observation_step_and_status_change(tmp_path: Path) -> None:
    # seed 3's fourth step is the first whose view has free floor far enough off to letter
    config = load_config(overrides=[f'bus.listen=["{free_tcp_endpoint()}"]', "episode.budget=4", "stop.rule=budget"])
    observations, frontiers, prompts = _Distinct(bb.OBSERVATION), _Distinct(bb.FRONTIER_CHOICES), _Distinct(bb.DIRECTION_PROMPTS)
    result = run_episode(RunRequest(seed=3, config=config, out_root=tmp_path, save_map=False),
                         extra_sinks=[observations, frontiers, prompts])
    assert result["status"] == "answered", result["reason"]
    rows = _rows(Path(result["folder"]) / RECORDING_FILE)

    frames = len(observations.seen)
    assert frames >= result["steps"] == 4
    for entity in (view.CAMERA, view.RGB, view.DEPTH, view.SEGMENTATION):
        assert len(rows[entity]) == frames, entity
    assert rows[view.CAMERA][0]["Pinhole:image_from_camera"] is not None
    labels = rows[view.SEGMENTATION][0]["AnnotationContext:context"][0]
    assert labels and all(entry["class_description"]["info"]["label"] for entry in labels)
    for letter in "ABCD":
        assert [row["step"] for row in rows[f"{view.ANSWERS}/{letter}"]] == [1, 2, 3, 4]
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
    _frontiers_and_prompts_match(rows, frontiers, prompts)


def _frontiers_and_prompts_match(rows: dict[str, list[dict[str, Any]]], frontiers: _Distinct, prompts: _Distinct) -> None:
    """Every frontier choice and visual prompt the board held is drawn once: the frontiers with
    their share of the weight, the chosen one marked; the prompt's points with letter and LSV."""
    chosen_lists = [choices for choices in frontiers.seen if choices]
    drawn = _drawn(rows[view.FRONTIERS], "Points2D")
    assert len(chosen_lists) >= 3 and len(drawn) == len(chosen_lists)
    for row, choices in zip(drawn, chosen_lists):
        labels = row["Points2D:labels"]
        assert labels == [("chosen " if c.chosen else "") + f"w {c.weight:.2f}" for c in choices]
        assert sum(label.startswith("chosen") for label in labels) == 1
        assert sum(float(label.split("w ")[1]) for label in labels) == pytest.approx(1.0, abs=0.01 * len(labels))
        assert len(row["Points2D:radii"]) == len(labels)
    lettered = [points for points in prompts.seen if points]
    assert lettered, "a semantic episode of four steps letters some view"
    for kind, entity in (("Points2D", view.MAP_PROMPTS), ("Points3D", view.WORLD_PROMPTS)):
        drawn = _drawn(rows[entity], kind)
        assert [row[f"{kind}:labels"] for row in drawn] == [[f"{p.letter} {p.value:.2f}" for p in points]
                                                             for points in lettered]
    world = _drawn(rows[view.WORLD_PROMPTS], "Points3D")[0]["Points3D:positions"]
    assert [value for point in world for value in point] == pytest.approx(
        [value for p in lettered[0] for value in (p.x, p.y, p.z)], abs=1e-5)


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


def test_a_robot_tabletop_recording_holds_the_arms_joints_after_each_skill(tmp_path: Path) -> None:
    out = tmp_path / "robot"
    assert main(["eval", "interactive", "--executor", "robot", "--tasks", "drawer-only", "--variants", "1",
                 "--out", str(out), "--record"]) == 0
    result = json.loads((out / "interactive-results.jsonl").read_text().splitlines()[0])
    rows = _rows(out / "recordings" / "drawer-only-0-robot" / RECORDING_FILE)
    runs = result["skill_times"]
    assert runs and [row["TextLog:text"][0] for row in rows[view.SKILL_LOG]] == [
        f"{run['skill']}: {'done' if run['ok'] else 'failed'}" for run in runs]
    joints = sorted(entity for entity in rows if entity.startswith(view.ARM_JOINTS + "/"))
    assert f"{view.ARM_JOINTS}/lift_joint" in joints and len(joints) == 8
    for entity in joints:
        assert [row["skill"] for row in rows[entity]] == list(range(1, len(runs) + 1)), entity
    assert rows["acsg"]


def test_an_act_that_opens_storage_records_the_arms_joints_of_each_skill(tmp_path: Path) -> None:
    """The hidden-evidence episode of home 60 opens storage: every skill its acts ran is logged, with
    the arm's joints by name."""
    config = load_config(overrides=[f'bus.listen=["{free_tcp_endpoint()}"]'])
    scenario = make_scenario(generate_home(60), 60, hidden=True).to_dict()
    runs = _Distinct(bb.LOOK_INSIDE_STATE)
    result = run_episode(RunRequest(seed=60, config=config, out_root=tmp_path, scenario=scenario, save_map=False),
                         extra_sinks=[runs])
    assert result["acts"], "the episode was to open storage"
    [state] = runs.seen
    rows = _rows(Path(result["folder"]) / RECORDING_FILE)
    assert [row["TextLog:text"][0] for row in rows[view.SKILL_LOG]] == [
        f"{name}: {'done' if ok else 'failed'}" for name, ok, _ in state.arm.runs]
    joints = sorted(entity for entity in rows if entity.startswith(view.ARM_JOINTS + "/"))
    assert f"{view.ARM_JOINTS}/lift_joint" in joints and len(joints) == 8
