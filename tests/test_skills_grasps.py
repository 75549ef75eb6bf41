"""The grasps that rest the closed fingertips on a thing's top, and the hand's clearances: plain arrays."""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.perception.grasp_poses import grasp_pose
from agent.perception.part_geometry import PartGeometry, hinge_axis
from skills.arm.grasps import (
    EDGE_INSET_M,
    FINGERTIP_M,
    HANDLE_TOP_M,
    OPEN_EDGE_INSET_M,
    TOP_PITCHES,
    closing_directions,
    fingertips_on,
    front_clearance,
    hand_bottom,
    hand_corners,
    handle_top_grasps,
    object_grasps,
    top_rotation,
)

#: A drawer's level bar 0.8 m high, its front 3.5 cm behind it, facing -y (towards a robot at y < 0).
DRAWER = PartGeometry("drawer", np.array([0.3, 0.05, 0.8]), np.array([1.0, 0.0, 0.0]), np.array([0.0, -1.0, 0.0]),
                      front_depth=0.035)


def _is_rotation(rotation: np.ndarray) -> bool:
    return bool(np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-9) and np.linalg.det(rotation) > 0.999)


def test_a_top_rotation_points_down_pitched_towards_a_side_and_closes_along_the_given_direction() -> None:
    closing, into = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    rotation = top_rotation(closing, math.radians(40), into)
    assert _is_rotation(rotation)
    assert rotation[:, 1] == pytest.approx(closing)
    assert rotation[:, 2] == pytest.approx([0.0, math.sin(math.radians(40)), -math.cos(math.radians(40))])
    assert top_rotation(np.array([0.0, 2.0, 0.0]))[:, 2] == pytest.approx([0.0, 0.0, -1.0])  # straight down


def test_fingertips_on_a_point_put_the_tcp_back_up_the_gripper_s_axis() -> None:
    rotation = top_rotation(np.array([0.0, 1.0, 0.0]), math.radians(30), np.array([1.0, 0.0, 0.0]))
    pose = fingertips_on(rotation, np.array([0.1, 0.2, 0.9]))
    assert pose[:3, 3] + FINGERTIP_M * pose[:3, 2] == pytest.approx([0.1, 0.2, 0.9])
    assert pose[:3, :3] == pytest.approx(rotation)


def test_grasps_from_above_rest_on_the_bar_along_it_and_lean_out_of_the_front() -> None:
    grasps = handle_top_grasps(DRAWER)
    assert len(grasps) == 2 * len(TOP_PITCHES) and all(g.touch and g.name == "from above" for g in grasps)
    top = DRAWER.handle_point + [0.0, 0.0, HANDLE_TOP_M]
    level_bottom = hand_bottom(grasp_pose(DRAWER))
    for grasp in grasps:
        pose = grasp_pose(DRAWER) @ grasp.offset
        assert _is_rotation(pose[:3, :3])
        assert pose[:3, 3] + FINGERTIP_M * pose[:3, 2] == pytest.approx(top)  # the fingertips on the bar's top
        assert abs(pose[:3, 1] @ DRAWER.handle_axis) == pytest.approx(1.0)  # the fingers' span along the bar
        assert pose[:3, 2] @ -DRAWER.normal > 0.45 and pose[2, 2] < -0.6  # down, and into the front
        assert front_clearance(pose, DRAWER) > 0.02  # the hand keeps 2 cm off the front ...
        corners = hand_corners(pose)
        high = corners[corners[:, 2] > top[2] + 0.095]  # ... and 3 cm before a bar 9.5 cm higher
        assert np.all((high - DRAWER.handle_point) @ DRAWER.normal > 0.03)
        assert hand_bottom(pose) > top[2] - 0.02 > level_bottom + 0.08  # no more than 2 cm below the bar's top


def test_only_a_drawer_s_level_bar_is_grasped_from_above() -> None:
    handle, hinge, normal = np.array([0.4, 0.05, 0.95]), np.array([0.0, 0.085, 0.95]), np.array([0.0, -1.0, 0.0])
    door = PartGeometry("door", handle, np.array([0.0, 0.0, 1.0]), normal, hinge, hinge_axis(handle, hinge, normal))
    upright = PartGeometry("drawer", handle, np.array([0.0, 0.0, 1.0]), normal, front_depth=0.035)
    assert handle_top_grasps(door) == [] and handle_top_grasps(upright) == []


def test_front_clearance_measures_the_hand_from_the_front_face_and_unknown_is_no_clearance() -> None:
    level = grasp_pose(DRAWER)  # the fingertips 9 mm past the bar's centre (the finger box: 11 mm)
    assert front_clearance(level, DRAWER) == pytest.approx(0.035 - 0.011)
    pushed = level.copy()
    pushed[:3, 3] -= 0.03 * DRAWER.normal  # 3 cm further in: 6 mm through the front
    assert front_clearance(pushed, DRAWER) == pytest.approx(-0.006)
    unknown = PartGeometry("drawer", DRAWER.handle_point, DRAWER.handle_axis, DRAWER.normal)
    assert front_clearance(level, unknown) == -math.inf


def test_closing_directions_start_across_the_line_of_sight_and_come_in_opposite_pairs() -> None:
    directions = closing_directions(np.array([0.05, 0.1, 0.1]), np.array([0.5, 0.5, 0.8]), (0.0, 0.0, 0.0))
    across = np.array([-1.0, 1.0, 0.0]) / math.sqrt(2)
    assert directions[0] == pytest.approx(across) and directions[1] == pytest.approx(-across)
    assert directions[2] == pytest.approx([1.0, 0.0, 0.0])  # then the box's narrower axis
    assert len(directions) == 8  # a diagonal is the line of sight's perpendicular: not twice
    assert all(abs(d[2]) == 0 and np.linalg.norm(d) == pytest.approx(1.0) for d in directions)


def test_objects_that_fit_are_grasped_around_and_wider_ones_by_their_top() -> None:
    point, base = np.array([0.3, 0.0, 0.9]), (0.0, 0.0, 0.0)
    can = object_grasps(np.array([0.066, 0.066, 0.12]), point, base, 0.075, 0.02)
    assert can and all(g.name == "fingers-around" and not g.touch and g.depth == 0.02 for g in can)
    long = object_grasps(np.array([0.05, 0.2, 0.1]), point, base, 0.075, 0.02)  # fits only across its width
    assert [tuple(np.round(g.rotation[:, 1], 6)) for g in long] == [(1.0, 0.0, 0.0), (-1.0, 0.0, 0.0)]
    box = object_grasps(np.array([0.18, 0.18, 0.14]), point, base, 0.075, 0.02)
    middle, edge = box[:8], box[8:]
    assert all(g.name == "fingertips-on-top" and g.touch for g in middle)  # every direction
    assert all(g.depth == -FINGERTIP_M and g.rotation[:, 2] == pytest.approx([0, 0, -1]) for g in middle)
    assert all(g.offset == pytest.approx(0.0) for g in middle)
    # then on the top just inside its near edge, straight down and leaning back towards the robot
    assert len(edge) == 8 and all(g.name == "fingertips-on-near-edge" and g.touch for g in edge)
    assert all(g.offset == pytest.approx([-(0.09 - EDGE_INSET_M), 0.0, 0.0]) for g in edge)
    assert [round(float(math.degrees(math.acos(-g.rotation[2, 2])))) for g in edge] == [0, 0, 30, 30, 50, 50, 65, 65]
    assert all(g.rotation[0, 2] > 0 for g in edge[2:])  # the approach leans away: the wrist nearer the base
    assert all(abs(g.rotation[:, 1] @ [1.0, 0.0, 0.0]) < 1e-9 for g in edge)  # closing across the line of sight


def test_fingertips_on_a_near_edge_seen_at_a_slant_stay_the_inset_inside_every_side() -> None:
    # recursive 1182 (tuning-wide): seen at a slant, the box's width along the line of sight put the
    # fingertips meant 6 cm inside its near side 2 cm inside it, and they held nothing.
    size, point, base = np.array([0.25, 0.32, 0.08]), np.array([0.3, 0.3, 0.83]), (0.0, 0.0, 0.0)
    for inset in (EDGE_INSET_M, OPEN_EDGE_INSET_M):
        edge = [g for g in object_grasps(size, point, base, 0.075, 0.02, edge_inset_m=inset)
                if g.name == "fingertips-on-near-edge"]
        assert len(edge) == 8
        for grasp in edge:  # towards the robot along the line of sight, the inset inside the side nearest
            assert grasp.offset == pytest.approx([-(0.125 - inset), -(0.125 - inset), 0.0], abs=1e-9)
            assert np.all(np.abs(grasp.offset[:2]) <= size[:2] / 2 - inset + 1e-9)


def test_fingers_close_along_the_line_of_sight_only_around_a_voxel_more_than_the_memory_saw() -> None:
    # occlusion 1006 (tuning-wide): a 7 cm shampoo bottle remembered 7 cm across and 6 cm deep; the
    # fingers, 6.4 cm apart, closed along its depth and one came down on the bottle.
    point, base = np.array([0.26, 0.0, 0.95]), (0.26, -0.7, 0.0)  # seen from straight before it
    bottle = object_grasps(np.array([0.07, 0.06, 0.2]), point, base, 0.064, 0.02)
    assert bottle and all(g.name == "fingertips-on-top" for g in bottle)
    wider = object_grasps(np.array([0.07, 0.06, 0.2]), point, base, 0.071, 0.02)  # 6 cm + a voxel fits
    assert wider and all(g.name == "fingers-around" for g in wider)
    assert any(abs(g.rotation[:, 1] @ [0.0, 1.0, 0.0]) == pytest.approx(1.0) for g in wider)  # along its depth
