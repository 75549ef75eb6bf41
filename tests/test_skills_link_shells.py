"""Where the arm's links bulge out of the tube round their skeleton (`skills.arm.link_shells`), from
the robot's own URDF and meshes, without a world."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from skills.arm.arm_model import READY
from skills.arm.clearance import CLEARANCE_M, Clearance
from skills.arm.frames import base_transform
from skills.arm.link_shells import (LINK_RADIUS_M, SLACK_M, bulge_centres, collision_vertices, link_spheres,
                                   rigid_segments)
from skills.arm.planner import ArmPlanner
from worlds.robot import CameraConfig
from worlds.robot_arm import robot_description

BASE = (0.3, -0.72, math.pi / 2)


@pytest.fixture(scope="module")
def planner() -> ArmPlanner:
    return ArmPlanner.from_description(robot_description(CameraConfig()))


def test_bulges_cover_every_vertex_the_tube_leaves_out_and_none_are_added_within_it() -> None:
    segments = np.array([[[0.0, 0.0, 0.0], [0.0, 0.0, 0.3]]])
    rng = np.random.default_rng(3)
    inside = np.c_[rng.uniform(-0.04, 0.04, (200, 2)), rng.uniform(0.0, 0.3, 200)]
    assert len(bulge_centres(inside, segments)) == 0
    housing = np.array([0.0, 0.13, 0.1]) + rng.uniform(-0.03, 0.03, (50, 3))  # a lump 13 cm aside
    vertices = np.vstack([inside, housing])
    centres = bulge_centres(vertices, segments)
    assert 1 <= len(centres) <= 4
    to_tube = np.abs(np.hypot(vertices[:, 0], vertices[:, 1]))
    to_bulge = np.linalg.norm(vertices[:, None] - centres[None], axis=2).min(axis=1)
    assert np.all((to_tube <= LINK_RADIUS_M + SLACK_M) | (to_bulge <= LINK_RADIUS_M + SLACK_M))


def test_a_link_s_mesh_is_read_from_the_urdf_and_a_mesh_not_here_is_left_to_the_tube(
        caplog: pytest.LogCaptureFixture) -> None:
    urdf = robot_description(CameraConfig())["urdf"]
    wrist = collision_vertices(urdf, "panda_joint5")
    assert wrist is not None and len(wrist) > 100
    assert np.ptp(wrist[:, 2]) > 0.3  # link 5 runs the forearm's length
    elsewhere = urdf.replace("/meshes/collision/link5.obj", "/meshes/collision/missing.obj")
    with caplog.at_level(logging.WARNING):
        assert collision_vertices(elsewhere, "panda_joint5") is None
    assert "cannot be read here" in caplog.text


def test_the_forearm_drawn_from_the_elbow_counts_for_the_wrist_link_it_runs_through(planner: ArmPlanner) -> None:
    lines = planner.kin.link_lines(planner.skeleton_first)
    postures = np.random.default_rng(0).uniform(planner.kin.lower, planner.kin.upper, size=(3, planner.kin.dof))
    rigid = rigid_segments(planner.kin, planner.skeleton_first, postures)
    wrist = [name for name, _ in lines].index("panda_joint5")
    longest = max(float(np.linalg.norm(b - a)) for a, b in rigid[wrist])
    assert longest > 0.3  # the forearm, 38 cm, though link 5's own stretch is a point


def test_a_corner_by_the_wrist_housing_is_touched_though_the_skeleton_s_tube_keeps_clear(
        planner: ArmPlanner) -> None:
    # recursive 1008 (tuning-wide): the wrist housing, 10 cm below the forearm's axis, came down on
    # a box's corner that the spheres along the skeleton kept clear of.
    clearance = Clearance(planner, base_transform(BASE))
    q = np.array(READY)
    skeleton, bulges = clearance.sphere_sets(q)
    assert len(bulges)
    tube = link_spheres(skeleton, step_m=0.01)
    gaps = np.linalg.norm(bulges[:, None] - tube[None], axis=2).min(axis=1)
    lump = bulges[int(np.argmax(gaps))]
    outward = (lump - tube[np.argmin(np.linalg.norm(tube - lump, axis=1))])
    corner = lump + outward / np.linalg.norm(outward) * (LINK_RADIUS_M + CLEARANCE_M / 2)
    points = corner + np.random.default_rng(1).uniform(-0.003, 0.003, (5, 3))
    assert np.linalg.norm(points[:, None] - skeleton[None], axis=2).min() > LINK_RADIUS_M + CLEARANCE_M
    touched = Clearance(planner, base_transform(BASE), obstacles=points).problem(q)
    assert touched is not None and "touch what stands near" in touched
