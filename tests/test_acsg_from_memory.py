"""Detections for the explorer read off the perception memory of real PyBullet frames."""

from __future__ import annotations

import numpy as np
import pytest

from agent.acsg.from_memory import memory_detections
from agent.mapping.camera import Intrinsics
from agent.perception.instances import Instance
from agent.perception.memory import InstanceMemory
from agent.perception.voxels import keys_of
from worlds.robot import CameraConfig
from worlds.sim import World
from worlds.tabletop import tabletop_variant


@pytest.fixture(scope="module")
def detections() -> dict[str, list]:
    """Occlusion variant 0: a nightstand (door under a drawer), a shampoo bottle in the door's swing,
    a book; three head-camera views from the robot's place in front of the table."""
    camera = CameraConfig()
    world = World(camera)
    try:
        base = world.start_tabletop(tabletop_variant("occlusion", 0))
        memory = InstanceMemory()
        intrinsics = Intrinsics(camera.width, camera.height, *camera.intrinsics())
        for turn in (0.0, 0.3, -0.3):
            world.place((base[0], base[1], base[2] + turn))
            frame = world.observe()
            memory.integrate_frame(frame.depth, frame.seg, frame.labels, intrinsics, frame.camera_pose)
        found = memory_detections(memory, frame.camera_pose[:3, 3])
    finally:
        world.close()
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


def test_the_bottle_in_the_door_swing_overlaps_its_swept_box_and_the_book_does_not(detections) -> None:
    lo, hi = (np.asarray(v) for v in _one(detections, "door").hints["swept"])

    def overlaps(detection) -> bool:
        a, b = detection.centroid - detection.extent / 2, detection.centroid + detection.extent / 2
        return bool(np.all(a < hi) and np.all(lo < b))

    assert overlaps(_one(detections, "shampoo"))
    assert not overlaps(_one(detections, "book"))
    assert "swept" in _one(detections, "drawer").hints


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
