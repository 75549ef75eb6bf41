"""The whole arm kept clear of the table, of what stands near and of what the hand carries: the
links as spheres (`skills.arm.clearance`), from the robot's own URDF, without a world."""

from __future__ import annotations

import math

import numpy as np
import pytest

from skills.arm.arm_model import READY
from skills.arm.clearance import CLEARANCE_M, LINK_RADIUS_M, Carried, Clearance, box_points
from skills.arm.link_shells import link_spheres
from skills.arm.frames import base_transform
from skills.arm.planner import ArmPlanner
from worlds.robot import CameraConfig
from worlds.robot_arm import STOWED, robot_description

BASE = (0.3, -0.72, math.pi / 2)
SURFACE = 0.755


@pytest.fixture(scope="module")
def planner() -> ArmPlanner:
    return ArmPlanner.from_description(robot_description(CameraConfig()))


def test_spheres_run_along_the_skeleton_no_further_apart_than_the_step() -> None:
    origins = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.3], [0.1, 0.0, 0.3], [0.1, 0.0, 0.3]])
    centres = link_spheres(origins, step_m=0.04)
    assert centres[0] == pytest.approx(origins[0]) and centres[-1] == pytest.approx(origins[-1])
    assert np.linalg.norm(np.diff(centres, axis=0), axis=1).max() <= 0.04 + 1e-9
    assert np.all(np.abs(centres[:, 1]) < 1e-12)  # on the segments, nowhere else


def test_links_over_the_table_keep_above_it_and_those_over_the_base_need_not(planner: ArmPlanner) -> None:
    base = base_transform(BASE)
    reaching = np.array([0.2, 0.0, 0.3, 0.0, -1.6, 0.0, 1.9, 0.785])  # the forearm out over the table
    centres = Clearance(planner, base).spheres(reaching)
    off_body = np.hypot(*(centres[:, :2] - base[:2, 3]).T) > planner.body_radius
    lowest = float(centres[off_body, 2].min()) - LINK_RADIUS_M
    assert Clearance(planner, base, surface_z=lowest - 0.02).problem(reaching) is None
    problem = Clearance(planner, base, surface_z=lowest).problem(reaching)
    assert problem is not None and f"onto the surface at {lowest:.3f} m" in problem
    assert Clearance(planner, base, surface_z=SURFACE).problem(np.array(STOWED)) is None  # folded over the base


def test_points_beside_a_link_are_touched_and_points_away_from_it_are_not(planner: ArmPlanner) -> None:
    q = np.array(READY)
    free = Clearance(planner, base_transform(BASE))
    elbow = free.spheres(q)[len(free.spheres(q)) // 2]
    beside = elbow + np.array([[LINK_RADIUS_M, 0.0, 0.0], [0.0, LINK_RADIUS_M, 0.0], [0.0, 0.0, LINK_RADIUS_M]])
    assert "(3 points)" in (Clearance(planner, base_transform(BASE), obstacles=beside).problem(q) or "")
    away = elbow + np.array([[0.3, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.3]])
    assert Clearance(planner, base_transform(BASE), obstacles=away).problem(q) is None
    assert Clearance(planner, base_transform(BASE), obstacles=beside[:2]).problem(q) is None  # noise


def test_the_forearm_is_checked_where_it_turns_aside_of_the_elbow(planner: ArmPlanner) -> None:
    # The forearm runs 8 cm aside of the elbow's axis, then 38 cm along to the wrist: checked along
    # the straight line between the two, a box at the elbow's side of the forearm went unseen.
    q = np.array(READY)
    first = planner.lift_index + 1
    skeleton = planner.kin.skeleton(q, first)
    elbow, corner, wrist = skeleton[3], skeleton[4], skeleton[5]
    assert np.linalg.norm(corner - elbow) == pytest.approx(0.0825, abs=1e-4)
    assert np.linalg.norm(wrist - corner) == pytest.approx(0.384, abs=1e-4)
    assert (corner - elbow) @ (wrist - corner) == pytest.approx(0.0, abs=1e-6)  # a right angle
    base = base_transform(BASE)
    line = wrist - elbow
    out = corner - elbow - ((corner - elbow) @ line) / (line @ line) * line  # away from the straight line
    world = base[:3, :3] @ (corner + 0.06 * out / np.linalg.norm(out)) + base[:3, 3]
    box = world + np.array([[0.0, 0.0, 0.0], [0.005, 0.0, 0.0], [0.0, 0.005, 0.0]])
    assert "(3 points)" in (Clearance(planner, base, obstacles=box).problem(q) or "")
    straight = link_spheres(np.array([elbow, wrist])) @ base[:3, :3].T + base[:3, 3]
    assert np.linalg.norm(straight[:, None] - box[None], axis=2).min() > LINK_RADIUS_M + CLEARANCE_M


def test_a_carried_box_reaching_up_to_the_forearm_is_touched(planner: ArmPlanner) -> None:
    q = np.array(READY)
    clearance = Clearance(planner, base_transform(BASE))
    tcp = base_transform(BASE) @ planner.kin.forward(q)
    small = Carried.held_at(tcp, tcp[:3, 3] - [0.0, 0.0, 0.05], np.array([0.08, 0.08, 0.1]))
    assert clearance.problem(q, small) is None
    wrist = clearance.spheres(q)[-1]
    tall = Carried.held_at(tcp, (tcp[:3, 3] + wrist) / 2, np.abs(wrist - tcp[:3, 3]) + 0.1)
    assert clearance.problem(q, tall) == "the arm's links would touch what the hand carries"


def test_the_hand_counts_only_on_the_way_to_a_grasp(planner: ArmPlanner) -> None:
    q = np.array(READY)
    tcp = base_transform(BASE) @ planner.kin.forward(q)
    finger = tcp[:3, 3] + tcp[:3, 1] * 0.05  # beside the TCP, where an open finger is
    points = finger + np.array([[0.0, 0.0, 0.0], [0.003, 0.0, 0.0], [0.0, 0.0, 0.003]])
    clearance = Clearance(planner, base_transform(BASE), obstacles=points)
    assert clearance.problem(q) is None
    assert clearance.problem(q, hand=True) == "the hand would touch what stands near"


def test_a_box_is_filled_with_points_out_to_its_corners() -> None:
    points = box_points(np.array([0.0, 0.0, 0.5]), np.array([0.1, 0.05, 0.2]))
    assert points.min(axis=0) == pytest.approx([-0.05, -0.025, 0.4])
    assert points.max(axis=0) == pytest.approx([0.05, 0.025, 0.6])
    assert len(np.unique(points[:, 2])) >= 11  # 2 cm apart at most
