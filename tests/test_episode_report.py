"""The evaluator's record of an episode: kept by the world, fetched once by the runtime, never seen
by the tree; and the route move_base says it drove."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import py_trees
import pytest

from worlds.bus.rpc import QueryFailed
from agent.app.config import load_config
from agent.mapping.occupancy import ExplorationMap, OccupancyConfig
from agent.app.runtime.local_world import LocalWorld, local_world
from agent.app.runtime.plots import save_map_png
from agent.app.runtime.run import RunRequest, run_episode
from worlds.bus.link import WorldLink
from worlds.evaluation import EpisodeRecord
from worlds.freespace import clearance
from worlds.home import HomeSpec, generate_home
from worlds.robot import CameraConfig
from worlds.route import driven_route
from worlds.scenario import Scenario, make_scenario
from worlds.storage_placement import home_storage
from worlds.things import Furniture

#: Seeds whose scenario asks about storage: seed 3's hidden-evidence one, seed 16's "Is the fridge in
#: the kitchen open or closed?" (a door-state question, which the act branch leaves alone).
HIDDEN_SEED, DOOR_STATE_SEED = 3, 16


def _facing_storage(seed: int, **drawn: Any) -> tuple[HomeSpec, Scenario, Furniture]:
    """The seed's scenario (``drawn`` as `make_scenario` is asked, e.g. hidden=True) with the robot
    1.6 m in front of the storage piece its question names, looking at it."""
    home = generate_home(seed)
    scenario = make_scenario(home, seed, **drawn)
    [piece] = [f for f in home.furniture if f.room == scenario.target["room"]
               and f.category == scenario.target["container"]]
    x, y, _ = piece.center
    start = (x + 1.6 * math.cos(piece.facing), y + 1.6 * math.sin(piece.facing), piece.facing + math.pi)
    return home, replace(scenario, start_pose=start), piece


def _link(served: LocalWorld) -> WorldLink:
    return WorldLink(served.session, served.keys, timeout_s=30.0)


def test_the_driven_route_is_the_path_cut_where_the_base_stopped() -> None:
    path = [(2.0, 0.0), (2.0, 2.0), (0.0, 2.0)]
    assert driven_route((0.0, 0.0), path, 4.0 + 2.0, (0.0, 2.0)) == [(0.0, 0.0), *path]
    assert driven_route((0.0, 0.0), path, 3.0, (2.0, 1.0)) == [(0.0, 0.0), (2.0, 0.0), (2.0, 1.0)]
    assert driven_route((0.0, 0.0), path, 0.0, (0.0, 0.0)) == [(0.0, 0.0)]


def test_rooms_entered_follow_the_route_in_order_from_the_start_room() -> None:
    home = generate_home(DOOR_STATE_SEED)
    scenario = make_scenario(home, DOOR_STATE_SEED)
    first, second = home.rooms[0], home.rooms[1]
    centre = [((r.rect[0] + r.rect[2]) / 2, (r.rect[1] + r.rect[3]) / 2) for r in (first, second)]
    record = EpisodeRecord(home, scenario, CameraConfig(), centre[0])
    assert record.rooms_entered == [first.name]
    record.drove([centre[0], centre[1], centre[0]], 2 * math.dist(*centre))  # straight, walls or not
    passed = record.report()["rooms_entered"]
    assert passed[0] == first.name and passed[-1] == second.name and len(passed) == len(set(passed))
    assert record.report()["travelled_m"] == pytest.approx(2 * math.dist(*centre), abs=1e-3)


def test_a_start_facing_the_storage_sees_it_at_step_0_and_only_head_frames_count() -> None:
    home, scenario, piece = _facing_storage(HIDDEN_SEED, hidden=True)
    [placement] = [p for p in home_storage(home) if p.furniture_id == piece.instance_id]
    with local_world() as served:
        link = _link(served)
        try:
            with pytest.raises(QueryFailed, match="episode_report: no home yet"):
                link.call("episode_report", {})
            link.call("reset", {"seed": HIDDEN_SEED, "scenario": scenario.to_dict()})
            link.call("observe", {"camera": "wrist"})
            link.call("observe", {})
            link.call("observe", {})
            report = link.call("episode_report", {}).meta
        finally:
            link.close()
    target = report["target"]
    assert target["kind"] == "storage"
    assert [t["id"] for t in target["things"]] == [piece.instance_id]
    assert set(target["ids"]) == {piece.instance_id, *placement.part_ids().values()}
    assert report["head_frames"] == 2
    seen = report["target_seen"]
    assert seen["step"] == 0 and 0 < seen["share"] <= 1
    assert seen["base_pose"][:2] == pytest.approx(scenario.start_pose[:2], abs=1e-3)
    assert report["rooms_entered"] == [home.room_at(*scenario.start_pose[:2])]
    assert {room["name"] for room in report["rooms"]} == {room.name for room in home.rooms}
    assert 0 < report["floor_seen_m2"] < report["free_floor_m2"] < home.area_m2
    assert report["travelled_m"] == 0


def test_moves_report_their_route_and_turning_aside_shows_more_floor() -> None:
    home, scenario, _ = _facing_storage(DOOR_STATE_SEED, kinds=("state",))
    x, y, yaw = scenario.start_pose
    back = (x + 0.3 * math.cos(yaw + math.pi), y + 0.3 * math.sin(yaw + math.pi))  # away from the fridge
    side = (back[0] + 0.2 * math.cos(yaw + math.pi / 2), back[1] + 0.2 * math.sin(yaw + math.pi / 2))
    assert min(clearance(home, *p) for p in (back, side)) > 0.3
    with local_world() as served:
        link = _link(served)
        try:
            link.call("reset", {"seed": DOOR_STATE_SEED, "scenario": scenario.to_dict()})
            link.call("observe", {})
            before = link.call("episode_report", {}).meta
            moved = link.call("move_base", {"path": [list(back), list(side)], "yaw": yaw + math.pi / 2}).meta
            link.call("observe", {})
            after = link.call("episode_report", {}).meta
        finally:
            link.close()
    assert moved["reached"]
    assert np.asarray(moved["driven"]) == pytest.approx(np.array([[x, y], back, side]), abs=1e-3)
    assert after["travelled_m"] == pytest.approx(moved["travelled_m"], abs=1e-3)
    assert after["floor_seen_m2"] > before["floor_seen_m2"]
    assert after["target_seen"] == before["target_seen"]  # the first sight stays the first
    assert after["floor_seen_by_frame"] == [before["floor_seen_m2"], after["floor_seen_m2"]]
    assert after["rooms_entered_by_frame"][0] == 1 and after["rooms_entered_by_frame"][1] == len(after["rooms_entered"])


def test_the_report_refuses_a_tabletop_and_a_scenario_about_nothing_in_the_home() -> None:
    home = generate_home(DOOR_STATE_SEED)
    nothing = replace(make_scenario(home, DOOR_STATE_SEED), target={"category": None, "colour": None,
                                                                     "room": "garden", "container": "fridge",
                                                                     "appliance": None})
    with local_world() as served:
        link = _link(served)
        try:
            with pytest.raises(QueryFailed, match=r"reset\.scenario\.target: no fridge in the garden"):
                link.call("reset", {"seed": DOOR_STATE_SEED, "scenario": nothing.to_dict()})
            link.call("reset", {"seed": 0, "tabletop": "door-only"})
            with pytest.raises(QueryFailed, match="episode_report: the world holds a tabletop scene"):
                link.call("episode_report", {})
            with pytest.raises(QueryFailed, match=r"episode_report\.step: unknown field"):
                link.call("episode_report", {"step": 1})
        finally:
            link.close()


@pytest.mark.slow
def test_an_episode_records_the_report_the_tree_never_saw(tmp_path: Path) -> None:
    home, scenario, piece = _facing_storage(DOOR_STATE_SEED, kinds=("state",))
    config = load_config(overrides=["bus.listen=[]", "episode.budget=2", "stop.rule=budget",
                                    "explore.method=fbe"])
    blackboards: list[dict] = []

    def keep_blackboard(_snapshot: dict) -> None:
        blackboards.append(dict(py_trees.blackboard.Blackboard.storage))

    result = run_episode(RunRequest(seed=DOOR_STATE_SEED, config=config, out_root=tmp_path,
                                    scenario=scenario.to_dict()), extra_sinks=[keep_blackboard])

    assert result["status"] == "answered", result["reason"]
    on_disk = json.loads((Path(result["folder"]) / "result.json").read_text())
    report = on_disk["evaluation"]
    assert report == result["evaluation"]
    assert report["target"]["kind"] == "storage" and report["target"]["things"][0]["id"] == piece.instance_id
    assert report["target_seen"]["step"] == 0 and report["target_seen"]["share"] > 0
    assert report["head_frames"] == result["steps"] == 2
    assert report["rooms_entered"][0] == home.room_at(*scenario.start_pose[:2])
    assert 0 < report["floor_seen_m2"] <= report["free_floor_m2"]
    assert (Path(result["folder"]) / "map.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # The tree ran with its usual blackboard and nothing of the report on it, at any tick.
    assert blackboards
    for board in blackboards:
        assert not any("report" in key or "evaluation" in key for key in board)
        assert not any(isinstance(value, dict) and "target_seen" in value for value in board.values())


@pytest.mark.parametrize("seen", [True, False])
def test_the_map_is_drawn_with_the_report_or_without_it(tmp_path: Path, seen: bool) -> None:
    home, scenario, _ = _facing_storage(DOOR_STATE_SEED, kinds=("state",))
    record = EpisodeRecord(home, scenario, CameraConfig(), scenario.start_pose[:2])
    report = record.report()
    if seen:
        report["target_seen"] = {"step": 0, "share": 0.2, "base_pose": list(scenario.start_pose)}
    start = scenario.start_pose
    result = {"question": scenario.question, "answer": "A", "answer_text": "Open", "ground_truth": scenario.answer,
              "ground_truth_text": scenario.answer_text, "status": "answered", "correct": False, "steps": 2}
    world_map = ExplorationMap(start[:2], OccupancyConfig())
    trajectory = [start, (start[0] + 0.5, start[1], start[2]), (start[0] + 0.5, start[1] + 0.5, 1.0)]
    for evaluation in (report, None):
        path = tmp_path / f"map-{evaluation is None}.png"
        save_map_png(path, world_map, trajectory, {**result, "evaluation": evaluation})
        assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_no_behaviour_skill_or_vlm_asks_for_the_report() -> None:
    root = Path(__file__).resolve().parent.parent
    sources = [path for folder in ("behaviours", "skills", "agent/vlm", "agent/eqa", "agent/perception",
                                   "agent/planning", "agent/mapping", "agent/acsg")
               for path in (root / folder).rglob("*.py")]
    assert sources
    asking = [str(path.relative_to(root)) for path in sources if "episode_report" in path.read_text()]
    assert asking == []
