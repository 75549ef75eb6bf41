"""Perception on real PyBullet frames of the world's own articulated storage.

A nightstand (a right-hinged door under a drawer) and a cabinet (one door) stand side by side,
fronts facing -y; the head camera looks at them from two bases. The memory must find each piece,
part and handle once, chain handle -> part -> piece, and the geometry read off it must agree with
the URDF's joints (worlds.urdf.joint_frame): the estimated door arc must end where the simulated
handle really goes. Segmentation ids are used here only to look up ground truth, never by the code
under test.
"""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from agent.mapping.camera import Intrinsics
from agent.perception.grasp_poses import opening_waypoints
from agent.perception.instances import Instance
from agent.perception.memory import InstanceMemory
from agent.perception.part_geometry import handle_geometry
from worlds.camera import render
from worlds.robot import CameraConfig
from worlds.scene import StorageBody, add_storage
from worlds.storage import storage_model
from worlds.storage_placement import StoragePlacement
from worlds.urdf import handle_boxes, joint_frame, part_transform

CAMERA = CameraConfig(width=320, height=240, hfov_deg=70.0, mount_height_m=1.1, pitch_deg=-30.0)
INTRINSICS = Intrinsics(CAMERA.width, CAMERA.height, *CAMERA.intrinsics())
BASES = ((-0.3, -0.6, math.pi / 2 + 0.25), (0.3, -0.6, math.pi / 2 - 0.25))


@pytest.fixture
def scene(client: int) -> tuple[int, list[StorageBody], dict]:
    """The two pieces loaded closed; returns (client, pieces, segmentation labels)."""
    seg: dict = {}
    pieces = []
    x = -0.5
    for k, (model, size) in enumerate((("nightstand", (0.45, 0.35, 0.5)), ("cabinet", (0.45, 0.33, 0.45)))):
        placement = StoragePlacement(k + 1, storage_model(model, np.random.default_rng(k + 1), size),
                                     (x + size[0] / 2, 0.4, 0.0, 0.0), 100 + 10 * k)
        label = {"id": k + 1, "category": model, "colour": "white"}
        piece, labels = add_storage(client, placement, label)
        pieces.append(piece)
        seg.update(labels)
        x += size[0] + 0.1
    return client, pieces, seg


def _observe(memory: InstanceMemory, client: int, seg: dict, base) -> np.ndarray:
    frame = render(client, CAMERA, base, seg)
    memory.integrate_frame(frame.depth, frame.seg, frame.labels, INTRINSICS, frame.camera_pose)
    return frame.camera_pose[:3, 3]


def _by_hint(memory: InstanceMemory, hint: int) -> Instance:
    found = [inst for inst in memory.live() if inst.hint == hint]
    assert len(found) == 1, f"{len(found)} live instances last seen as segment {hint}"
    return found[0]


def test_real_frames_give_one_instance_per_thing_chained_handle_part_piece(scene) -> None:
    client, pieces, seg = scene
    memory = InstanceMemory()
    for base in BASES:
        _observe(memory, client, seg, base)
    expected = 2 + sum(2 * len(piece.placement.model.parts) for piece in pieces)
    assert len(memory.live()) == expected
    for piece in pieces:
        carcass = _by_hint(memory, piece.placement.furniture_id)
        ids = piece.placement.part_ids()
        for part in piece.placement.model.parts:
            front, handle = _by_hint(memory, ids[part.name]), _by_hint(memory, ids[part.handle])
            assert front.label == ("drawer" if part.kind == "drawer" else "door") and handle.label == "handle"
            assert handle.parent == front.id and front.parent == carcass.id


def test_geometry_from_real_frames_matches_the_urdf_joints(scene) -> None:
    client, pieces, seg = scene
    memory = InstanceMemory()
    eye = None
    for base in BASES:
        eye = _observe(memory, client, seg, base)
    for piece in pieces:
        placement, ids = piece.placement, piece.placement.part_ids()
        for part in placement.model.parts:
            geometry = handle_geometry(memory, _by_hint(memory, ids[part.handle]).id, eye)
            assert geometry.kind == part.kind
            assert math.degrees(math.acos(np.clip(geometry.normal @ (0.0, -1.0, 0.0), -1, 1))) < 5.0
            bar = placement.to_world(handle_boxes(placement.model, part)[0].center)
            assert np.linalg.norm(geometry.handle_point - bar) < 0.02
            if part.kind == "door":
                origin, axis = joint_frame(placement.model, part)
                assert np.linalg.norm((geometry.hinge_point - placement.to_world(origin))[:2]) < 0.02
                assert np.allclose(geometry.hinge_axis, axis, atol=0.02)


def test_the_estimated_arc_ends_where_the_opened_door_handle_is_and_the_old_one_is_forgotten(scene) -> None:
    client, pieces, seg = scene
    memory = InstanceMemory()
    eye = None
    for base in BASES:
        eye = _observe(memory, client, seg, base)
    cabinet = pieces[1]
    placement = cabinet.placement
    door = next(part for part in placement.model.parts if part.kind == "door")
    handle = _by_hint(memory, placement.part_ids()[door.handle])
    geometry = handle_geometry(memory, handle.id, eye)
    angle = 1.0
    end = opening_waypoints(geometry, angle)[-1]
    moved = part_transform(placement.model, door, angle) @ np.r_[handle_boxes(placement.model, door)[0].center, 1.0]
    assert np.linalg.norm(end[:3, 3] - placement.to_world(moved[:3])) < 0.025
    p.resetJointState(cabinet.body, cabinet.links[door.name], angle, physicsClientId=client)
    _observe(memory, client, seg, BASES[1])
    assert memory.get(handle.id).gone
