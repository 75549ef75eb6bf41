"""Detections for the explorer read off the perception memory of real PyBullet frames."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.acsg.decision import STORAGE_LABELS, RuleDecisionModule, _boxes_overlap
from agent.acsg.from_memory import door_sweep, memory_detections
from agent.mapping.camera import Intrinsics
from agent.perception.instances import Instance
from agent.perception.memory import InstanceMemory
from agent.perception.voxels import keys_of
from worlds.robot import CameraConfig
from worlds.sim import World
from worlds.tabletop import tabletop_variant


def _head_view_memory(task: str, seed: int) -> tuple[InstanceMemory, np.ndarray]:
    """The memory of three head-camera views of a tabletop variant from the robot's place in
    front of the table, and where the camera looked from."""
    camera = CameraConfig()
    world = World(camera)
    try:
        base = world.start_tabletop(tabletop_variant(task, seed))
        memory = InstanceMemory()
        intrinsics = Intrinsics(camera.width, camera.height, *camera.intrinsics())
        for turn in (0.0, 0.3, -0.3):
            world.place((base[0], base[1], base[2] + turn))
            frame = world.observe()
            memory.integrate_frame(frame.depth, frame.seg, frame.labels, intrinsics, frame.camera_pose)
    finally:
        world.close()
    return memory, frame.camera_pose[:3, 3]


def _named_in_the_way(task: str, seed: int) -> set[tuple[int, int]]:
    """(thing, part) world ids of what the rule verifier's test, on three head views of a variant,
    finds in the way of each part's opening."""
    memory, eye = _head_view_memory(task, seed)
    found = memory_detections(memory, eye)
    world_id = {d.instance: memory.get(int(d.instance)).hint for d in found}
    parts = [d for d in found if "swept" in d.hints]
    things = [d for d in found if d.label not in ("table", "door", "drawer", "handle", *STORAGE_LABELS)]
    return {(world_id[thing.instance], world_id[part.instance]) for part in parts for thing in things
            if _boxes_overlap(*(np.asarray(v) for v in thing.hints["box"]),
                              *(np.asarray(v) for v in part.hints["swept"]), RuleDecisionModule().sweep_margin_m)}


@pytest.fixture(scope="module")
def detections() -> dict[str, list]:
    """Occlusion variant 0: a nightstand (door under a drawer), a shampoo bottle in the door's swing,
    a book; three head-camera views from the robot's place in front of the table."""
    found = memory_detections(*_head_view_memory("occlusion", 0))
    by_label: dict[str, list] = {}
    for detection in found:
        by_label.setdefault(detection.label, []).append(detection)
    return by_label


def _one(detections: dict[str, list], label: str):
    assert len(detections.get(label, [])) == 1, f"{label}: {detections.get(label)}"
    return detections[label][0]


def test_relations_follow_the_scene(detections) -> None:
    table, nightstand = _one(detections, "table"), _one(detections, "nightstand")
    door, drawer = _one(detections, "door"), _one(detections, "drawer")
    assert table.parent is None
    assert (nightstand.parent, nightstand.relation) == (table.instance, "on")
    for thing in ("shampoo", "book"):
        assert (_one(detections, thing).parent, _one(detections, thing).relation) == (table.instance, "on")
    assert (door.parent, door.relation) == (drawer.parent, drawer.relation) == (nightstand.instance, "belongs")
    handles = detections["handle"]
    assert sorted(h.parent for h in handles) == sorted([door.instance, drawer.instance])
    assert all(h.relation == "belongs" for h in handles)


def test_each_detection_carries_the_box_around_what_was_seen_of_it(detections) -> None:
    for detection in (d for found in detections.values() for d in found):
        lo, hi = (np.asarray(v) for v in detection.hints["box"])
        assert np.allclose(hi - lo, detection.extent, atol=1e-3)
        assert np.all(lo < detection.centroid) and np.all(detection.centroid < hi)


def test_the_bottle_in_the_door_swing_overlaps_its_swept_box_and_the_book_does_not(detections) -> None:
    lo, hi = (np.asarray(v) for v in _one(detections, "door").hints["swept"])

    def overlaps(detection) -> bool:
        a, b = detection.centroid - detection.extent / 2, detection.centroid + detection.extent / 2
        return _boxes_overlap(a, b, lo, hi)

    assert overlaps(_one(detections, "shampoo"))
    assert not overlaps(_one(detections, "book"))
    assert "swept" in _one(detections, "drawer").hints


def test_a_door_sweeps_past_the_quarter_turn_over_its_hinges_side_boxed_cell_by_cell() -> None:
    # A door 0.5 m wide and 2 cm thick, its hinge at x = 0, its free edge at x = 0.5, opening
    # towards -y (a negative turn about +z, so a positive one about -z).
    front = (np.array([0.0, 0.0, 0.8]), np.array([0.5, 0.02, 1.2]))
    lo, hi = door_sweep(front, np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0]), math.radians(100.0))
    assert np.min(lo[:, 0]) == pytest.approx(0.5 * math.cos(math.radians(100.0)), abs=0.005)  # 8.7 cm past
    assert np.min(lo[:, 1]) == pytest.approx(-0.5, abs=0.005)
    assert np.all(lo[:, 2] == 0.8) and np.all(hi[:, 2] == 1.2)  # turning about z leaves heights

    def in_way(x: float, y: float) -> bool:
        return _boxes_overlap(np.array([x - 0.01, y - 0.01, 0.9]), np.array([x + 0.01, y + 0.01, 1.0]), lo, hi)

    assert in_way(-0.04, -0.25)  # beside the hinge, where the door swings on past square
    assert in_way(0.3, -0.3)  # on the quarter circle
    assert not in_way(0.42, -0.42)  # the square's far corner, which the door never reaches
    lo90, _ = door_sweep(front, np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0]), math.pi / 2)
    assert np.min(lo90[:, 0]) == pytest.approx(0.0, abs=1e-9)  # at the quarter turn, not past the hinge


@pytest.mark.parametrize("task, seed, in_the_way", [
    ("occlusion", 1116, {(6, 9), (7, 9)}),  # a jar beside a cabinet door's hinge, a carton before the door
    ("occlusion", 1054, {(6, 8)}),  # a can 3 cm beside a door's hinge
    ("door-only", 1089, set()),  # a mug on the next cabinet's top, beside the door's hinge, behind its front
    ("drawer-only", 1007, set()),  # a book before a chest, clear of where its bottom drawer comes out
])
def test_what_is_named_in_a_parts_way_is_what_the_scene_puts_there(task: str, seed: int,
                                                                    in_the_way: set[tuple[int, int]]) -> None:
    # Of 800 tuning-wide variants (1000-1159 of every task), the test on the first head views
    # names the scene's blockers in every one (`TabletopScene.blockers`, which sweeps a door to its
    # joint limit, past square). Judged by a box laid about the mean of a thing's points and a
    # square before each door, it was wrong in two (1116, 1007); by the box seen and that square,
    # 1054 too; by the box seen and one box round the whole swing, 1089.
    scene = tabletop_variant(task, seed)
    parts = {(pl.furniture_id, part.name): pl.first_part_id + 2 * k
             for _, pl in scene.storage for k, part in enumerate(pl.model.parts)}
    assert {(thing, parts[piece, part]) for thing, piece, part in scene.blockers()} == in_the_way
    assert _named_in_the_way(task, seed) == in_the_way


def test_a_thing_seen_only_from_above_stands_on_the_surface_under_it() -> None:
    # A can the wrist camera saw straight down: its top disc, 12 cm over the table, and no side.
    memory = InstanceMemory()
    xs, ys = np.meshgrid(np.arange(-0.5, 0.5, 0.01), np.arange(-0.4, 0.4, 0.01))
    slab = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 0.75)])
    angles = np.linspace(0.0, 2 * np.pi, 30)
    disc = np.column_stack([0.2 + 0.03 * np.cos(angles), -0.3 + 0.03 * np.sin(angles), np.full(30, 0.87)])
    for key, (label, points) in enumerate((("table", slab), ("can", disc))):
        keys, hits = keys_of(points, memory.config.voxel_m)
        memory.instances[key] = Instance(key, label, None, keys, hits, memory.config.voxel_m, 0, 0)
    table, can = sorted(memory_detections(memory, np.array([0.0, -0.8, 1.5])), key=lambda d: d.label != "table")
    assert (can.parent, can.relation) == (table.instance, "on")


def test_a_thing_the_memory_merged_names_the_ids_it_absorbed() -> None:
    # One mug seen from above and from beside, first taken for two, then found to be one.
    memory = InstanceMemory()
    top = np.column_stack([np.linspace(0.0, 0.05, 20), np.zeros(20), np.full(20, 0.86)])
    side = np.column_stack([np.zeros(20), np.full(20, -0.03), np.linspace(0.76, 0.85, 20)])
    for key, points in enumerate((top, side)):
        keys, hits = keys_of(points, memory.config.voxel_m)
        memory.instances[key] = Instance(key, "mug", None, keys, hits, memory.config.voxel_m, 0, 0)
    assert [d.hints.get("absorbed") for d in memory_detections(memory, np.array([0.0, -0.8, 1.5]))] == [None, None]
    memory.merge(0, 1)
    (mug,) = memory_detections(memory, np.array([0.0, -0.8, 1.5]))
    assert mug.instance == "0" and mug.hints["absorbed"] == ("1",)
