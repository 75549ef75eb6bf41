"""Part geometry from points: handle direction, door or drawer, front normal, hinge, TCP paths.

Point clouds are drawn with seeded noise around known truths (a bar, a front board); the last
tests read the geometry off the instance memory of ray-cast frames of a cabinet and a drawer chest.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from agent.perception.directions import GeometryError, front_normal, principal_axis, snap_handle_axis
from agent.perception.grasp_poses import (
    LEAST_EXTENT_M,
    closing_waypoints,
    drawer_floor,
    grasp_pose,
    opening_waypoints,
    pregrasp_pose,
    seen_extent,
    standing_extent,
    top_grasp_point,
)
from agent.perception.memory import InstanceMemory
from agent.perception.part_geometry import PartGeometry, classify_part, handle_geometry, part_geometry
from agent.perception.part_motion import moved_geometry, rotation_about
from test_perception_scene import INTRINSICS, Box, Front, look_at, render, storage

NOISE_M = 0.002


def _angle_deg(a: np.ndarray, b: np.ndarray, signed: bool = True) -> float:
    cos = float(np.dot(a, b) / np.linalg.norm(a) / np.linalg.norm(b))
    return math.degrees(math.acos(np.clip(cos if signed else abs(cos), -1.0, 1.0)))


def _basis(direction: np.ndarray) -> np.ndarray:
    """Columns: ``direction`` and two unit vectors across it."""
    d = direction / np.linalg.norm(direction)
    helper = np.array([1.0, 0.0, 0.0]) if abs(d[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    a = np.cross(d, helper)
    a /= np.linalg.norm(a)
    return np.column_stack([d, a, np.cross(d, a)])


def _bar(rng: np.random.Generator, centre, direction, length: float = 0.15, thick: float = 0.016,
         count: int = 300) -> np.ndarray:
    """Noisy points in a square bar along ``direction`` (what a handle's voxels look like)."""
    local = rng.uniform(-0.5, 0.5, (count, 3)) * np.array([length, thick, thick])
    return local @ _basis(np.asarray(direction, float)).T + centre + rng.normal(0, NOISE_M, (count, 3))


def _board(rng: np.random.Generator, x: tuple[float, float], z: tuple[float, float], y: float = 0.0,
           count: int = 1500) -> np.ndarray:
    """Noisy points on the plane y = ``y`` over an x, z rectangle: a front seen from -y."""
    pts = np.column_stack([rng.uniform(*x, count), np.full(count, y), rng.uniform(*z, count)])
    return pts + rng.normal(0, NOISE_M, pts.shape)


def _yawed(points: np.ndarray, yaw: float) -> np.ndarray:
    return points @ rotation_about(np.array([0.0, 0.0, 1.0]), yaw).T


CAMERA = np.array([0.1, -1.0, 1.3])  # in front of fronts at y = 0, facing -y


def _door(rng: np.random.Generator, handle_x: float, yaw: float = 0.0) -> PartGeometry:
    """A 0.3 x 0.4 m door in y = 0 (normal -y) with a vertical handle 4.3 cm out at ``handle_x``."""
    front = _board(rng, (0.0, 0.3), (0.8, 1.2))
    handle = _bar(rng, (handle_x, -0.043, 1.0), (0.0, 0.0, 1.0), length=0.14)
    return part_geometry(_yawed(handle, yaw), _yawed(front, yaw), _yawed(CAMERA[None], yaw)[0])


def _drawer(rng: np.random.Generator) -> PartGeometry:
    front = _board(rng, (0.0, 0.4), (0.8, 0.95))
    handle = _bar(rng, (0.2, -0.043, 0.875), (1.0, 0.0, 0.0), length=0.16)
    return part_geometry(handle, front, CAMERA)


# --- directions --------------------------------------------------------------------------------


def test_pca_finds_a_noisy_handles_direction_within_5_degrees() -> None:
    rng = np.random.default_rng(0)
    for _ in range(25):
        truth = rng.normal(size=3)
        points = _bar(rng, rng.uniform(-1, 1, 3), truth)
        assert _angle_deg(principal_axis(points), truth, signed=False) < 5.0


def test_the_snap_makes_near_vertical_handles_vertical_and_others_horizontal() -> None:
    tilt = math.radians(10)
    assert np.allclose(snap_handle_axis(np.array([math.sin(tilt), 0.0, math.cos(tilt)])), (0, 0, 1))
    flat = snap_handle_axis(np.array([1.0, 1.0, 0.5]))
    assert flat[2] == 0.0 and np.isclose(np.linalg.norm(flat), 1.0) and _angle_deg(flat, (1, 1, 0)) < 1e-6


def test_a_horizontal_handle_means_a_drawer_and_a_vertical_one_a_door() -> None:
    assert classify_part(np.array([0.0, 0.0, 1.0])) == "door"
    assert classify_part(np.array([1.0, 0.0, 0.0])) == "drawer"
    assert classify_part(np.array([0.0, 0.6, 0.8])) == "door"  # |z| 0.8 > 0.7
    assert classify_part(np.array([0.0, 0.8, 0.6])) == "drawer"
    rng = np.random.default_rng(1)
    door, drawer = _door(rng, 0.25), _drawer(rng)
    assert door.kind == "door" and door.joint == "revolute" and door.hinge_axis is not None
    assert drawer.kind == "drawer" and drawer.joint == "prismatic" and drawer.hinge_point is None


def test_the_front_normal_points_towards_the_camera() -> None:
    rng = np.random.default_rng(2)
    for yaw in rng.uniform(-math.pi, math.pi, 6):
        front = _yawed(_board(rng, (0.0, 0.4), (0.8, 1.2)), yaw)
        truth = _yawed(np.array([[0.0, -1.0, 0.0]]), yaw)[0]
        seen_from_front = _yawed(CAMERA[None], yaw)[0]
        assert _angle_deg(front_normal(front, seen_from_front), truth) < 3.0
        behind = _yawed(np.array([[0.1, 1.0, 1.3]]), yaw)[0]
        assert _angle_deg(front_normal(front, behind), -truth) < 3.0


def test_the_most_common_normal_ignores_the_carcass_side_next_to_the_front() -> None:
    rng = np.random.default_rng(3)
    front = _board(rng, (0.0, 0.4), (0.8, 1.2), count=1200)
    side = np.column_stack([np.full(500, 0.42), rng.uniform(0.0, 0.3, 500), rng.uniform(0.8, 1.2, 500)])
    normal = front_normal(np.vstack([front, side + rng.normal(0, NOISE_M, side.shape)]), CAMERA + (1.0, 0, 0))
    assert _angle_deg(normal, (0.0, -1.0, 0.0)) < 3.0 and normal[2] == 0.0


# --- hinges ------------------------------------------------------------------------------------


@pytest.mark.parametrize("yaw", [0.0, 0.7, -2.0])
def test_the_hinge_is_on_the_side_of_the_front_away_from_the_handle(yaw: float) -> None:
    rng = np.random.default_rng(4)
    for handle_x, hinge_x, axis_z in ((0.25, 0.0, -1.0), (0.05, 0.3, 1.0)):
        door = _door(rng, handle_x, yaw)
        hinge = _yawed(np.array([[hinge_x, 0.0, 1.0]]), yaw)[0]
        assert np.linalg.norm((door.hinge_point - hinge)[:2]) < 0.01
        assert abs(door.hinge_point[2] - door.handle_point[2]) < 1e-9  # level with the handle
        # a door hinged at its left (smaller local x) turns about -z, as worlds.urdf has it
        assert np.allclose(door.hinge_axis, (0.0, 0.0, axis_z))
        assert abs(door.radius - math.hypot(handle_x - hinge_x, 0.043)) < 0.01


def test_a_door_with_a_horizontal_handle_is_a_flap_hinged_at_its_far_edge() -> None:
    rng = np.random.default_rng(5)
    front = _board(rng, (0.0, 0.4), (0.5, 0.8))
    handle = _bar(rng, (0.2, -0.043, 0.76), (1.0, 0.0, 0.0), length=0.16)  # near the top edge
    flap = part_geometry(handle, front, CAMERA, kind="door")
    assert flap.kind == "door" and abs(flap.hinge_point[2] - 0.5) < 0.01
    assert _angle_deg(flap.hinge_axis, (1.0, 0.0, 0.0), signed=False) < 3.0
    first_step = opening_waypoints(flap, math.radians(5), n=1)[1][:3, 3] - flap.handle_point
    assert first_step @ flap.normal > 0 and first_step[2] < 0  # the top comes out and down


# --- TCP poses ---------------------------------------------------------------------------------


def test_the_grasp_pose_approaches_along_minus_normal_with_fingers_across_the_bar() -> None:
    rng = np.random.default_rng(6)
    for geometry in (_door(rng, 0.25, yaw=0.4), _drawer(rng)):
        pose = grasp_pose(geometry)
        rotation = pose[:3, :3]
        assert np.allclose(rotation.T @ rotation, np.eye(3)) and np.isclose(np.linalg.det(rotation), 1.0)
        assert np.allclose(rotation[:, 2], -geometry.normal)  # approach
        assert np.allclose(rotation[:, 0], geometry.handle_axis)  # bar between the fingers
        assert abs(rotation[:, 1] @ geometry.handle_axis) < 1e-12  # fingers close across it
        assert np.allclose(pose[:3, 3], geometry.handle_point)
        assert np.allclose(pregrasp_pose(geometry)[:3, 3], geometry.handle_point + 0.03 * geometry.normal)


def test_arc_waypoints_keep_the_radius_and_end_turned_by_the_angle() -> None:
    rng = np.random.default_rng(7)
    door = _door(rng, 0.25, yaw=0.3)
    angle = math.radians(80)
    poses = opening_waypoints(door, angle)
    assert len(poses) == 17  # 5 degree steps by default
    assert np.allclose(poses[0], grasp_pose(door))
    radii = [_distance_to_line(p[:3, 3], door.hinge_point, door.hinge_axis) for p in poses]
    assert np.allclose(radii, door.radius, atol=1e-9) and door.radius > 0.2
    turn = poses[-1][:3, :3] @ poses[0][:3, :3].T
    assert np.allclose(turn, rotation_about(door.hinge_axis, angle))
    assert math.isclose(_angle_deg(poses[-1][:3, 2], poses[0][:3, 2]), 80.0, abs_tol=1e-6)
    assert (poses[1][:3, 3] - poses[0][:3, 3]) @ door.normal > 0  # the handle comes out first
    assert np.allclose(poses[-1][:3, 3], moved_geometry(door, angle).handle_point)
    assert np.allclose(poses[-1][:3, 2], -moved_geometry(door, angle).normal)
    heights = [p[2, 3] for p in poses]
    assert np.allclose(heights, heights[0])  # a vertical hinge keeps the handle's height


def test_line_waypoints_pull_the_handle_along_the_normal_by_the_distance() -> None:
    rng = np.random.default_rng(8)
    drawer = _drawer(rng)
    poses = opening_waypoints(drawer, 0.3, n=6)
    assert len(poses) == 7
    assert np.allclose(poses[-1][:3, 3] - poses[0][:3, 3], 0.3 * drawer.normal)
    steps = np.diff([p[:3, 3] for p in poses], axis=0)
    assert np.allclose(steps, 0.05 * drawer.normal)
    assert all(np.allclose(p[:3, :3], poses[0][:3, :3]) for p in poses)
    assert len(opening_waypoints(drawer, 0.3)) == 16  # 2 cm steps by default


def test_closing_retraces_opening_and_a_negative_amount_closes_an_open_part() -> None:
    rng = np.random.default_rng(9)
    door = _door(rng, 0.05)
    opening, closing = opening_waypoints(door, 1.2, n=8), closing_waypoints(door, 1.2, n=8)
    assert all(np.allclose(a, b) for a, b in zip(opening, closing[::-1]))
    opened = moved_geometry(door, 1.2)
    back = opening_waypoints(opened, -1.2, n=8)
    assert np.allclose(back[-1], grasp_pose(door))


def test_bad_input_is_refused_by_name() -> None:
    rng = np.random.default_rng(10)
    with pytest.raises(GeometryError, match="handle_points"):
        part_geometry(np.zeros((1, 3)), _board(rng, (0, 0.3), (0, 0.3)), CAMERA)
    with pytest.raises(GeometryError, match="kind"):
        part_geometry(_bar(rng, (0, -0.04, 0.1), (0, 0, 1)), _board(rng, (0, 0.3), (0, 0.3)), CAMERA, kind="flap")
    with pytest.raises(GeometryError, match="front_points"):
        part_geometry(_bar(rng, (0, -0.04, 0.1), (0, 0, 1)), np.zeros((5, 2)), CAMERA)
    with pytest.raises(GeometryError, match="n"):
        opening_waypoints(_drawer(rng), 0.2, n=0)


# --- from the memory ---------------------------------------------------------------------------


def test_geometry_read_off_the_memory_of_a_rendered_cabinet_and_drawer_chest() -> None:
    cabinet = storage(2, "cabinet", (0.15, 0.55), (0.23, 0.53), (0.75, 1.15),
                      (Front("door", (0.152, 0.348), (0.77, 1.13), "left"),
                       Front("door", (0.352, 0.548), (0.77, 1.13), "right")))
    chest = storage(10, "drawer chest", (-0.5, -0.1), (0.23, 0.53), (0.75, 1.1),
                    (Front("drawer", (-0.498, -0.102), (0.77, 0.93)), Front("drawer", (-0.498, -0.102), (0.932, 1.08))))
    table = Box.at(1, "table", (0.0, 0.1, 0.73), (1.6, 0.9, 0.04))
    memory = InstanceMemory()
    eyes = [np.array([-0.2, -0.8, 1.45]), np.array([0.25, -0.75, 1.35])]
    for eye in eyes:
        pose = look_at(eye, (0.0, 0.3, 0.9))
        depth, seg, labels = render([table, *cabinet, *chest], pose)
        memory.integrate_frame(depth, seg, labels, INTRINSICS, pose)
    handles = memory.with_label("handle")
    assert len(handles) == 4
    geometries = [handle_geometry(memory, handle.id, eyes[1]) for handle in handles]
    assert all(_angle_deg(g.normal, (0.0, -1.0, 0.0)) < 5.0 for g in geometries)
    doors = sorted((g for g in geometries if g.kind == "door"), key=lambda g: g.handle_point[0])
    drawers = [g for g in geometries if g.kind == "drawer"]
    assert len(doors) == 2 and len(drawers) == 2
    left, right = doors
    assert abs(left.hinge_point[0] - 0.152) < 0.015 and np.allclose(left.hinge_axis, (0, 0, -1))
    assert abs(right.hinge_point[0] - 0.548) < 0.015 and np.allclose(right.hinge_axis, (0, 0, 1))
    for door, bar_x in ((left, 0.308), (right, 0.392)):
        assert np.linalg.norm(door.handle_point - (bar_x, 0.21 - 0.035, 0.95)) < 0.02
        assert abs(door.hinge_point[1] - 0.21) < 0.01  # on the front's outer face
    assert all(_angle_deg(g.handle_axis, (1.0, 0.0, 0.0), signed=False) < 5.0 for g in drawers)


def _distance_to_line(point: np.ndarray, origin: np.ndarray, direction: np.ndarray) -> float:
    d = point - origin
    return float(np.linalg.norm(d - (d @ direction) * direction))


def test_the_pick_point_is_the_mean_of_the_highest_points() -> None:
    rng = np.random.default_rng(11)
    body = rng.uniform((-0.04, -0.04, 0.75), (0.04, 0.04, 0.85), (400, 3))
    lid = np.column_stack([rng.uniform(0.0, 0.02, (50, 2)), np.full(50, 0.9)])
    assert np.allclose(top_grasp_point(np.vstack([body, lid])), (*lid[:, :2].mean(axis=0), 0.9))


def test_a_thing_seen_only_from_above_still_has_some_height() -> None:
    """A box in a drawer is seen through the opening, its top only: its points span no height, yet
    a pick needs one (how deep to grasp, how high to lift); it gets two voxels' worth."""
    rng = np.random.default_rng(5)
    top_only = np.column_stack([rng.uniform(0.0, 0.14, (60, 1)), rng.uniform(0.0, 0.05, (60, 1)), np.full(60, 0.835)])
    assert seen_extent(top_only) == pytest.approx([0.14, 0.05, LEAST_EXTENT_M], abs=0.005)
    whole = rng.uniform((0.0, 0.0, 0.78), (0.1, 0.06, 0.85), (400, 3))
    assert seen_extent(whole) == pytest.approx(np.ptp(whole, axis=0))
    with pytest.raises(GeometryError, match="points"):
        seen_extent(np.zeros((0, 3)))


def test_a_thing_whose_lower_part_is_hidden_reaches_down_to_what_it_stands_on() -> None:
    """A box in a cabinet seen from above over the cabinet's floor: its upper 7 cm seen, the floor
    under it at 0.76 m. It reaches down to the floor; the cabinet's walls beside it, a shelf over
    it and a floor further down than anything could hide do not count."""
    rng = np.random.default_rng(6)
    upper = rng.uniform((0.0, 0.0, 0.82), (0.14, 0.14, 0.89), (300, 3))
    xs, ys = np.meshgrid(np.arange(-0.1, 0.25, 0.01), np.arange(-0.1, 0.25, 0.01))
    floor = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 0.76)])
    walls = np.array([(x, y, z) for x in (-0.005, 0.145) for y in np.arange(0.0, 0.14, 0.01)
                      for z in np.arange(0.76, 1.0, 0.01)])
    shelf = floor + [0.0, 0.0, 0.3]
    assert standing_extent(upper, np.vstack([floor, walls, shelf]))[2] == pytest.approx(0.89 - 0.76, abs=0.003)
    assert standing_extent(upper, np.vstack([walls, shelf]))[2] == pytest.approx(np.ptp(upper[:, 2]))
    assert standing_extent(upper, floor - [0.0, 0.0, 0.3])[2] == pytest.approx(np.ptp(upper[:, 2]))
    assert standing_extent(upper, None) == pytest.approx(seen_extent(upper))


def test_a_thing_on_a_table_reaches_no_lower_than_the_tables_top() -> None:
    """A box standing over a table's corner hides the top under it, and the table's leg is seen
    below: the box reaches down to the top (0.755 m), not to the leg (recursive 1250 of
    tuning-wide: taken 23 cm tall of its 10); without the top's height, to the leg's top."""
    rng = np.random.default_rng(7)
    box = rng.uniform((0.45, -0.35, 0.78), (0.6, -0.25, 0.855), (300, 3))
    leg = np.array([(x, y, z) for x in (0.5, 0.51) for y in (-0.31, -0.3) for z in np.arange(0.63, 0.715, 0.01)])
    assert standing_extent(box, leg)[2] == pytest.approx(box[:, 2].max() - leg[:, 2].max())
    assert standing_extent(box, leg, floor_z=0.755)[2] == pytest.approx(box[:, 2].max() - 0.755)
    floor = np.column_stack([rng.uniform(0.46, 0.59, (50, 2)) * [1, 0] + [0, -0.3], np.full(50, 0.76)])
    assert standing_extent(box, np.vstack([leg, floor]), floor_z=0.755)[2] == pytest.approx(box[:, 2].max() - 0.76)


def _open_drawer(floor_z: float = 0.98, top_z: float = 1.17) -> np.ndarray:
    """A drawer pulled out, as the memory has it: its floor (x 0.34-0.67, y -0.04-0.2), its front
    (y -0.06, from 2 cm under the floor to ``top_z``) and its side walls, 1 cm voxels."""
    xs, ys = np.meshgrid(np.arange(0.34, 0.675, 0.01), np.arange(-0.04, 0.205, 0.01))
    floor = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, floor_z)])
    xs, zs = np.meshgrid(np.arange(0.34, 0.675, 0.01), np.arange(floor_z - 0.02, top_z + 0.005, 0.01))
    front = np.column_stack([xs.ravel(), np.full(xs.size, -0.06), zs.ravel()])
    ys, zs = np.meshgrid(np.arange(-0.04, 0.205, 0.01), np.arange(floor_z, top_z + 0.005, 0.01))
    sides = [np.column_stack([np.full(ys.size, x), ys.ravel(), zs.ravel()]) for x in (0.34, 0.67)]
    return np.vstack([floor, front, *sides])


def test_a_box_in_an_open_drawer_reaches_down_to_the_drawer_s_floor_showing_around_it() -> None:
    """A box 5 cm tall in a drawer, seen from above only (one layer of points at its top), the
    drawer's floor showing around it, and under it what the memory saw there before the drawer was
    pulled out over it, 12 cm lower (recursive 1264 of tuning-wide: taken 17 cm tall). It reaches
    down to the floor; the drawer's front and walls, which spread one way each, are not its floor."""
    xs, ys = np.meshgrid(np.arange(0.47, 0.605, 0.01), np.arange(0.02, 0.095, 0.01))
    box = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 1.035)])
    drawer = _open_drawer()
    covered = (drawer[:, 0] > 0.46) & (drawer[:, 0] < 0.61) & (drawer[:, 1] > 0.01) & (drawer[:, 1] < 0.1) \
        & (drawer[:, 2] < 0.99)
    drawer = drawer[~covered]  # the box hides the floor under it
    stale = box - [0.0, 0.0, 0.17]
    assert drawer_floor(box, drawer) == (pytest.approx(0.98), True)
    assert standing_extent(box, stale, floor_z=0.755)[2] == pytest.approx(0.17)
    assert standing_extent(box, stale, floor_z=0.755, stands_on_z=0.98)[2] == pytest.approx(1.035 - 0.98)
    # the floor hidden all round (a box filling the drawer), the drawer's lowest point bounds it
    walls_only = drawer[drawer[:, 2] > 0.985]
    low = drawer_floor(box, np.vstack([walls_only, drawer[drawer[:, 1] < -0.05]]))
    assert low == (pytest.approx(0.96), False)
    # a thing on the chest's top over the drawer, or beside the drawer, stands in no drawer
    assert drawer_floor(box + [0.0, 0.0, 0.2], drawer) is None
    assert drawer_floor(box + [0.5, 0.0, 0.0], drawer) is None
    assert drawer_floor(box, np.zeros((0, 3))) is None
