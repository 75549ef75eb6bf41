"""Articulated storage furniture: generated URDF in real PyBullet and real Pinocchio, parts, slots, sight."""

from __future__ import annotations

import math

import numpy as np
import pinocchio
import pybullet as p
import pytest

from worlds.camera import render
from worlds.robot import CameraConfig
from worlds.scene import add_box, add_storage, link_indices, load_storage, urdf_file
from worlds.storage import HANDLE_REACH, MODELS, Box, StorageModel, storage_model
from worlds.storage_placement import StoragePlacement
from worlds.urdf import handle_boxes, part_transform, storage_urdf

SEEDS = (0, 1, 2, 3)
CASES = [(model, seed) for model in MODELS for seed in SEEDS]
WHITE = (0.9, 0.9, 0.9, 1.0)


def _model(name: str, seed: int) -> StorageModel:
    return storage_model(name, np.random.default_rng(seed))


def _joint(client: int, body: int, name: str) -> float:
    return p.getJointState(body, link_indices(client, body)[name], physicsClientId=client)[0]


@pytest.mark.parametrize(("name", "seed"), CASES)
def test_urdf_loads_in_pybullet_and_pinocchio_with_one_joint_per_part(client: int, name: str, seed: int) -> None:
    model = _model(name, seed)
    text = storage_urdf(model, WHITE)
    body = load_storage(client, model, WHITE, (0.0, 0.0, 0.0, 0.3))
    links = link_indices(client, body)
    assert set(links) == {part.name for part in model.parts} | {part.handle for part in model.parts}
    for part in model.parts:
        info = p.getJointInfo(body, links[part.name], physicsClientId=client)
        assert info[2] == (p.JOINT_REVOLUTE if part.joint == "revolute" else p.JOINT_PRISMATIC)
        assert (info[8], info[9]) == pytest.approx((part.lower, part.upper))
    for source in (pinocchio.buildModelFromXML(text), pinocchio.buildModelFromUrdf(str(urdf_file(text)))):
        assert list(source.names)[1:] == [f"{part.name}_joint" for part in model.parts]
        assert source.nq == len(model.parts)
        assert np.allclose(source.upperPositionLimit, [part.upper for part in model.parts])
        for part in model.parts:
            assert source.existFrame(part.handle)


def test_same_seed_same_model_and_round_trip() -> None:
    for name in MODELS:
        first, again = _model(name, 7), _model(name, 7)
        assert first == again
        assert StorageModel.from_dict(first.to_dict()) == first
        assert storage_urdf(first, WHITE) == storage_urdf(again, WHITE)


def test_models_have_the_parts_their_kind_implies() -> None:
    for seed in range(20):
        kinds = {name: [part.kind for part in _model(name, seed).parts] for name in MODELS}
        assert set(kinds["cabinet"]) == {"door"} and 1 <= len(kinds["cabinet"]) <= 2
        assert set(kinds["drawer_chest"]) == {"drawer"} and 2 <= len(kinds["drawer_chest"]) <= 4
        assert kinds["wardrobe"] == ["door", "door"]
        assert kinds["nightstand"] == ["door", "drawer"]
        assert set(kinds["fridge"]) == {"door"} and 1 <= len(kinds["fridge"]) <= 2
        assert kinds["dishwasher"] == ["flap"]
        assert {"door", "drawer"} == set(kinds["counter"])
        assert _model("dishwasher", seed).parts[0].hinge == "bottom"


@pytest.mark.parametrize(("name", "seed"), CASES)
def test_every_joint_stops_at_its_limits(client: int, name: str, seed: int) -> None:
    model = _model(name, seed)
    body = load_storage(client, model, WHITE, (0.0, 0.0, 0.0, 0.0))
    links = link_indices(client, body)
    for part in model.parts:
        for target, limit in ((part.upper + 0.5, part.upper), (part.lower - 0.5, part.lower)):
            p.setJointMotorControl2(body, links[part.name], p.POSITION_CONTROL, targetPosition=target, force=200.0,
                                    physicsClientId=client)
            for _ in range(480):
                p.stepSimulation(physicsClientId=client)
            value = _joint(client, body, part.name)
            assert value == pytest.approx(limit, abs=0.02), (part.name, target)
            assert part.lower - 0.02 <= value <= part.upper + 0.02


@pytest.mark.parametrize(("name", "seed"), CASES)
def test_a_part_left_half_open_stays_there_under_gravity(client: int, name: str, seed: int) -> None:
    model = _model(name, seed)
    half = {part.name: part.upper / 2 for part in model.parts}
    body = load_storage(client, model, WHITE, (0.0, 0.0, 0.0, 1.0), half)
    for _ in range(240):
        p.stepSimulation(physicsClientId=client)
    for part in model.parts:
        assert _joint(client, body, part.name) == pytest.approx(half[part.name], abs=0.005), part.name


def test_a_door_gives_way_to_a_push_then_comes_to_rest_and_stays(client: int) -> None:
    model = _model("cabinet", 1)
    door = model.parts[0]
    body = load_storage(client, model, WHITE, (0.0, 0.0, 0.0, 0.0))
    link = link_indices(client, body)[door.name]
    for _ in range(30):
        p.applyExternalTorque(body, link, (0.0, 0.0, 2.0 * (1 if door.hinge == "right" else -1)), p.WORLD_FRAME,
                              physicsClientId=client)
        p.stepSimulation(physicsClientId=client)
    for _ in range(240):
        p.stepSimulation(physicsClientId=client)
    rest = _joint(client, body, door.name)
    for _ in range(240):
        p.stepSimulation(physicsClientId=client)
    assert 0.05 < rest < door.upper - 0.05
    assert _joint(client, body, door.name) == pytest.approx(rest, abs=1e-3)


@pytest.mark.parametrize(("name", "seed"), CASES)
def test_handles_are_links_of_their_own_fixed_to_their_part(client: int, name: str, seed: int) -> None:
    model = _model(name, seed)
    body = load_storage(client, model, WHITE, (0.0, 0.0, 0.0, 0.0))
    links = link_indices(client, body)
    for part in model.parts:
        info = p.getJointInfo(body, links[part.handle], physicsClientId=client)
        assert info[2] == p.JOINT_FIXED and info[16] == links[part.name]
        lo, hi = (np.array(v) for v in p.getAABB(body, links[part.handle], physicsClientId=client))
        extent = hi - lo
        assert np.argmax(extent) == (2 if part.kind == "door" else 0)  # vertical on doors, across on the rest
        assert lo[1] < -model.size[1] / 2 - 0.02 and lo[1] >= -model.size[1] / 2 - HANDLE_REACH - 0.01


@pytest.mark.parametrize(("name", "seed"), CASES)
def test_slots_lie_inside_the_carcass_and_their_drawer(name: str, seed: int) -> None:
    model = _model(name, seed)
    w, d, h = model.size
    inside = np.array([w / 2, d / 2, h])
    for slot in model.slots:
        box = slot.box()
        assert np.all(box.size > np.array([0.05, 0.05, 0.03])), slot
        assert np.all(np.abs(box.lo()[:2]) <= inside[:2]) and np.all(np.abs(box.hi()[:2]) <= inside[:2])
        assert box.lo()[2] >= 0 and box.hi()[2] <= h
        assert not any(_overlap(box, panel) for panel in model.panels), slot.name
        if slot.part is not None:
            tray = model.part(slot.part).tray
            assert tray is not None and tray.contains(Box(box.name, box.center, (box.size[0], box.size[1], 0.0)))
            assert slot.access == slot.part
        else:
            assert model.part(slot.access).kind in ("door", "flap")
    assert {slot.access for slot in model.slots} == {part.name for part in model.parts}


def _overlap(a: Box, b: Box) -> bool:
    return bool(np.all(a.lo() < b.hi() - 1e-9) and np.all(b.lo() < a.hi() - 1e-9))


def test_a_drawer_slot_moves_with_its_drawer(client: int) -> None:
    model = _model("drawer_chest", 2)
    drawer = model.parts[-1]
    slot = next(s for s in model.slots if s.part == drawer.name)
    pose = (1.0, -0.5, 0.0, 0.7)
    body = load_storage(client, model, WHITE, pose)
    link = link_indices(client, body)[drawer.name]
    placement = StoragePlacement(5, model, pose, 100)
    closed = placement.slot_spot(slot.name, 0.0)
    frame = np.array(p.getLinkState(body, link, physicsClientId=client)[4])
    p.resetJointState(body, link, drawer.upper, physicsClientId=client)
    moved_frame = np.array(p.getLinkState(body, link, physicsClientId=client)[4])
    opened = StoragePlacement(5, model, pose, 100, ((drawer.name, drawer.upper),)).slot_spot(slot.name, 0.0)
    assert np.allclose(opened - closed, moved_frame - frame, atol=1e-6)
    assert np.linalg.norm(opened - closed) == pytest.approx(drawer.upper)
    # the handle, as the helpers compute it, also followed the drawer in PyBullet
    handle = np.array(p.getLinkState(body, link_indices(client, body)[drawer.handle], physicsClientId=client)[4])
    local = (part_transform(model, drawer, drawer.upper) @ np.array([*handle_boxes(model, drawer)[0].center, 1.0]))[:3]
    assert np.allclose(placement.to_world(local), handle, atol=1e-5)


# A cabinet against nothing, a white mug in its lowest slot, the head camera 1.6 m in front of it.
_CAMERA = CameraConfig(width=160, height=120, hfov_deg=70.0, mount_height_m=1.3, pitch_deg=-30.0)


def _scene_with_hidden_mug(client: int, name: str, slot_of: str) -> tuple[StoragePlacement, int, dict]:
    model = _model(name, 3)
    placement = StoragePlacement(2, model, (0.0, 0.0, 0.0, 0.0), 10)
    carcass = {"id": 2, "category": name, "colour": "white"}
    piece, labels = add_storage(client, placement, carcass)
    floor = add_box(client, (0.0, 0.0, -0.01), (6.0, 6.0, 0.02), (0.5, 0.5, 0.5, 1.0))
    labels[(floor, -1)] = {"id": 1, "category": "floor", "colour": "blue"}
    slot = next(s for s in model.slots if s.access == next(p_.name for p_ in model.parts if p_.kind == slot_of))
    spot = placement.slot_spot(slot.name, 0.04)
    shape = p.createCollisionShape(p.GEOM_BOX, halfExtents=[0.04] * 3, physicsClientId=client)
    visual = p.createVisualShape(p.GEOM_BOX, halfExtents=[0.04] * 3, rgbaColor=(0.9, 0.1, 0.1, 1),
                                 physicsClientId=client)
    mug = p.createMultiBody(0.0, shape, visual, spot.tolist(), physicsClientId=client)
    labels[(mug, -1)] = {"id": 99, "category": "mug", "colour": "red"}
    return placement, piece.body, labels


@pytest.mark.parametrize(("name", "kind"), [("cabinet", "door"), ("nightstand", "drawer"), ("dishwasher", "flap")])
def test_what_is_inside_is_hidden_until_its_part_opens(client: int, name: str, kind: str) -> None:
    placement, body, labels = _scene_with_hidden_mug(client, name, kind)
    view = (0.0, -1.6, math.pi / 2)
    part = next(part for part in placement.model.parts if part.kind == kind)
    closed = render(client, _CAMERA, view, labels)
    assert 99 not in closed.seg and placement.part_ids()[part.name] in closed.seg
    assert {label["id"] for label in closed.labels} == set(np.unique(closed.seg[closed.seg >= 0]).tolist())
    p.resetJointState(body, link_indices(client, body)[part.name], part.upper, physicsClientId=client)
    if kind == "drawer":  # the mug rides in the drawer
        mug = next(b for (b, _), label in labels.items() if label["id"] == 99)
        opened = StoragePlacement(2, placement.model, placement.pose, 10, ((part.name, part.upper),))
        slot = next(s for s in placement.model.slots if s.part == part.name)
        p.resetBasePositionAndOrientation(mug, opened.slot_spot(slot.name, 0.04).tolist(), (0, 0, 0, 1),
                                          physicsClientId=client)
    seen = render(client, _CAMERA, view, labels)
    assert (seen.seg == 99).sum() > 5
    assert 99 in {label["id"] for label in seen.labels}


def test_parts_and_handles_are_segmented_as_instances_of_their_own(client: int) -> None:
    placement, _, labels = _scene_with_hidden_mug(client, "nightstand", "door")
    frame = render(client, _CAMERA, (0.0, -1.2, math.pi / 2), labels)
    categories = {label["id"]: label["category"] for label in frame.labels}
    ids = placement.part_ids()
    assert categories[2] == "nightstand"
    assert categories[ids["door_0"]] == "door" and categories[ids["drawer_0"]] == "drawer"
    assert categories[ids["door_0_handle"]] == "handle" and categories[ids["drawer_0_handle"]] == "handle"
    assert set(categories) == set(np.unique(frame.seg[frame.seg >= 0]).tolist())
