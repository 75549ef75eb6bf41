"""Tabletop suites after RoboEXP's Table I: variants, their PyBullet scenes and their ground-truth ACSGs."""

from __future__ import annotations

import json
import math
from pathlib import Path

import networkx as nx
import numpy as np
import pybullet as p
import pytest

from worlds.camera import render
from worlds.robot import CameraConfig
from worlds.scene import link_indices
from worlds.tabletop import TASKS, VARIANTS, build_tabletop, tabletop_variant, write_tabletop_suites
from worlds.tabletop_scene import TABLE_ID, TabletopScene

ALL = [(task, seed) for task in TASKS for seed in range(VARIANTS)]


def _graph(acsg: dict) -> nx.DiGraph:
    graph = nx.DiGraph()
    for node in acsg["nodes"]:
        graph.add_node(node["id"], **node)
    for edge in acsg["edges"]:
        assert edge["source"] in graph and edge["target"] in graph, edge
        graph.add_edge(edge["source"], edge["target"], type=edge["type"], relation=edge["relation"])
    assert graph.number_of_edges() == len(acsg["edges"])  # no edge twice
    return graph


def _hidden(scene: TabletopScene) -> dict[int, str]:
    """Object id -> the action that reveals it, from the scene's own data."""
    shells = {o.instance_id for o in scene.objects if o.shape == "shell"}
    pieces = {placement.furniture_id: placement for _, placement in scene.storage}
    hidden = {}
    for obj in scene.objects:
        if obj.slot is not None:
            placement = pieces[obj.parent]
            hidden[obj.instance_id] = f"open:{placement.part_ids()[placement.model.slot(obj.slot).access]}"
        elif obj.parent in shells:
            hidden[obj.instance_id] = f"pick:{obj.parent}"
    return hidden


def test_same_seed_same_variant() -> None:
    for task in TASKS:
        first, again = tabletop_variant(task, 4), tabletop_variant(task, 4)
        assert first == again
        assert json.dumps(first.to_dict()) == json.dumps(again.to_dict())
        assert first.ground_truth_acsg() == again.ground_truth_acsg()
        assert TabletopScene.from_dict(json.loads(json.dumps(first.to_dict()))) == first


@pytest.mark.parametrize("task", TASKS)
def test_a_tasks_ten_variants_are_distinct(task: str) -> None:
    scenes = {json.dumps(tabletop_variant(task, seed).to_dict()) for seed in range(VARIANTS)}
    assert len(scenes) == VARIANTS


@pytest.mark.parametrize(("task", "seed"), ALL)
def test_variant_builds_with_all_its_bodies_and_hides_what_it_should(client: int, task: str, seed: int) -> None:
    scene = tabletop_variant(task, seed)
    seg = build_tabletop(client, scene)
    bodies = {body for body, _ in seg}
    assert len(bodies) == p.getNumBodies(physicsClientId=client) == 1 + len(scene.storage) + len(scene.objects)
    assert {label["id"] for label in seg.values()} == set(scene.labels())
    for _, placement in scene.storage:
        body = next(b for (b, link), label in seg.items() if link == -1 and label["id"] == placement.furniture_id)
        names = {name for part in placement.model.parts for name in (part.name, part.handle)}
        assert set(link_indices(client, body)) == names
    # Seen from the robot's side, nothing hidden shows; every part and handle is its own instance.
    camera = CameraConfig(width=160, height=120, hfov_deg=80.0, mount_height_m=1.5, pitch_deg=-35.0)
    frame = render(client, camera, (0.0, -1.3, math.pi / 2), seg)
    assert not set(_hidden(scene)) & set(np.unique(frame.seg).tolist())
    assert {label["id"] for label in frame.labels} == set(np.unique(frame.seg[frame.seg >= 0]).tolist())
    assert {"handle", "table"} <= {label["category"] for label in frame.labels}


@pytest.mark.parametrize(("task", "seed"), ALL)
def test_ground_truth_is_a_dag_with_exactly_the_nodes_the_scene_implies(task: str, seed: int) -> None:
    scene = tabletop_variant(task, seed)
    acsg = scene.ground_truth_acsg()
    graph = _graph(acsg)
    assert nx.is_directed_acyclic_graph(graph)
    objects = {n for n, d in graph.nodes(data=True) if d["kind"] == "object"}
    assert objects == {f"o{i}" for i in scene.labels()}
    shells = {o.instance_id for o in scene.objects if o.shape == "shell"}
    blockers = {obstacle for obstacle, _, _ in scene.blockers()}
    opens = {f"open:{i}" for _, pl in scene.storage for part in pl.model.parts for i in [pl.part_ids()[part.name]]}
    picks = {f"pick:{i}" for i in shells | blockers}
    assert {n for n, d in graph.nodes(data=True) if d["kind"] == "action"} == opens | picks
    for action in opens | picks:
        target = graph.nodes[action]["target"]
        assert graph.edges[target, action]["type"] == "object-action"
    # every hidden object is revealed by exactly the action that uncovers it, and nothing else is
    hidden = _hidden(scene)
    reveals = {(s, t) for s, t, d in graph.edges(data=True) if d["relation"] == "reveals"}
    assert reveals == {(action, f"o{obj}") for obj, action in hidden.items()}
    # every object has one parent, and the table is the only root
    for obj in scene.objects:
        parents = [s for s, _, d in graph.in_edges(f"o{obj.instance_id}", data=True) if d["type"] == "object-object"]
        assert len(parents) == 1
    roots = [n for n in graph if graph.in_degree(n) == 0]
    assert roots == [f"o{TABLE_ID}"]


@pytest.mark.parametrize("task", TASKS)
def test_task_specific_structure(task: str) -> None:
    for seed in range(VARIANTS):
        scene = tabletop_variant(task, seed)
        graph = _graph(scene.ground_truth_acsg())
        kinds = {part.kind for _, pl in scene.storage for part in pl.model.parts}
        preconditions = [(s, t) for s, t, d in graph.edges(data=True) if d["type"] == "action-action"]
        hidden = _hidden(scene)
        assert hidden, "every variant hides something"
        if task == "drawer-only":
            assert kinds == {"drawer"}
        if task == "door-only":
            assert kinds == {"door"}
        if task == "drawer-door":
            assert kinds == {"door", "drawer"}
            assert {graph.nodes[graph.nodes[a]["target"]]["category"] for a in hidden.values()} == {"door", "drawer"}
        if task == "occlusion":
            assert preconditions and all(s.startswith("pick:") and t.startswith("open:") for s, t in preconditions)
        else:
            assert not preconditions
        if task == "recursive":  # a reveal chain at least two actions deep
            assert _reveal_depth(graph, hidden) >= 2


def _reveal_depth(graph: nx.DiGraph, hidden: dict[int, str]) -> int:
    """The most actions one must take in turn to see a hidden object (open, then pick, then pick...)."""
    def depth(obj: str) -> int:
        action = next((s for s, _, d in graph.in_edges(obj, data=True) if d["relation"] == "reveals"), None)
        if action is None:
            return 0
        return 1 + depth(graph.nodes[action]["target"])
    return max(depth(f"o{obj}") for obj in hidden)


@pytest.mark.parametrize("seed", range(VARIANTS))
def test_an_obstacle_really_stops_its_door_and_the_door_opens_without_it(client: int, seed: int) -> None:
    scene = tabletop_variant("occlusion", seed)
    seg = build_tabletop(client, scene)
    obstacle, piece_id, part_name = scene.blockers()[0]
    body = next(b for (b, link), label in seg.items() if link == -1 and label["id"] == piece_id)
    placement = next(pl for _, pl in scene.storage if pl.furniture_id == piece_id)
    part = placement.model.part(part_name)
    link = link_indices(client, body)[part_name]

    def swing() -> float:
        p.resetJointState(body, link, 0.0, physicsClientId=client)
        p.setJointMotorControl2(body, link, p.VELOCITY_CONTROL, targetVelocity=1.0, force=5.0, physicsClientId=client)
        for _ in range(720):
            p.stepSimulation(physicsClientId=client)
        return p.getJointState(body, link, physicsClientId=client)[0]

    assert swing() < part.upper - 0.2
    for obj in scene.blockers():  # take every obstacle of this door away
        if obj[1:] == (piece_id, part_name):
            other = next(b for (b, link_), label in seg.items() if link_ == -1 and label["id"] == obj[0])
            p.resetBasePositionAndOrientation(other, (0.0, 0.0, -5.0), (0, 0, 0, 1), physicsClientId=client)
    assert swing() == pytest.approx(part.upper, abs=0.02)
    assert obstacle in {o.instance_id for o in scene.objects if o.relation == "on" and o.parent == TABLE_ID}


def test_suites_are_written_one_jsonl_per_task(tmp_path: Path) -> None:
    paths = write_tabletop_suites(tmp_path)
    assert sorted(path.name for path in paths) == sorted(f"{task}.jsonl" for task in TASKS)
    for path in paths:
        lines = [json.loads(line) for line in path.read_text().splitlines()]
        assert [line["seed"] for line in lines] == list(range(VARIANTS))
        for line in lines:
            scene = TabletopScene.from_dict(line["scene"])
            assert scene == tabletop_variant(line["task"], line["seed"])
            assert line["acsg"] == scene.ground_truth_acsg()
    assert not list(tmp_path.glob("*.tmp"))
