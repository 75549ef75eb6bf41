"""Arm kinematics against PyBullet, IK on reachable and unreachable poses, and Cartesian paths.

The robot here is pybullet_data's Franka Panda on a vertical prismatic lift, spliced by hand (see
`lift_panda_urdf`): the library itself only ever sees a URDF string, joint names and a frame.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pybullet as p
import pybullet_data
import pytest

from agent.app.bench.arm import bench_arm
from skills.arm.ik_solver import plan_cartesian_path, solve_ik
from skills.arm.kinematics import ArmKinematics
from skills.arm.tcp_paths import arc_poses, line_poses
from skills.arm.trajectory import JointLimits, plan_trajectory

JOINTS = ["lift_joint"] + [f"panda_joint{i}" for i in range(1, 8)]
TCP = "panda_grasptarget"


def lift_panda_urdf() -> str:
    """The Panda (without meshes) on a 0–0.6 m vertical lift, mounted off-centre and turned, so FK
    exercises a non-trivial root-to-arm transform."""
    panda = ET.parse(Path(pybullet_data.getDataPath()) / "franka_panda" / "panda.urdf").getroot()
    for link in panda.findall("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    robot = ET.Element("robot", name="lift_panda")
    ET.SubElement(robot, "link", name="world")
    lift = ET.SubElement(robot, "link", name="lift_link")
    inertial = ET.SubElement(lift, "inertial")
    ET.SubElement(inertial, "mass", value="1.0")
    ET.SubElement(inertial, "inertia", ixx="0.01", ixy="0", ixz="0", iyy="0.01", iyz="0", izz="0.01")
    joint = ET.SubElement(robot, "joint", name="lift_joint", type="prismatic")
    ET.SubElement(joint, "origin", xyz="0.1 -0.05 0.2", rpy="0 0 0.3")
    ET.SubElement(joint, "parent", link="world")
    ET.SubElement(joint, "child", link="lift_link")
    ET.SubElement(joint, "axis", xyz="0 0 1")
    ET.SubElement(joint, "limit", lower="0", upper="0.6", velocity="0.3", effort="500")
    mount = ET.SubElement(robot, "joint", name="arm_mount", type="fixed")
    ET.SubElement(mount, "origin", xyz="0.05 0 0.02", rpy="0 0 0")
    ET.SubElement(mount, "parent", link="lift_link")
    ET.SubElement(mount, "child", link="panda_link0")
    robot.extend(list(panda))
    return ET.tostring(robot, encoding="unicode")


@pytest.fixture(scope="module")
def urdf() -> str:
    return lift_panda_urdf()


@pytest.fixture(scope="module")
def kin(urdf: str) -> ArmKinematics:
    return ArmKinematics(urdf, JOINTS, TCP)


def random_configurations(kin: ArmKinematics, count: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return np.array([kin.random_configuration(rng) for _ in range(count)])


def rotation_angle(a: np.ndarray, b: np.ndarray) -> float:
    return math.acos(np.clip((np.trace(a.T @ b) - 1) / 2, -1.0, 1.0))


def test_limits_come_from_the_urdf(kin: ArmKinematics) -> None:
    assert kin.joint_names == tuple(JOINTS)
    assert kin.dof == 8
    assert (kin.lower[0], kin.upper[0]) == (0.0, 0.6)
    assert kin.upper[4] == 0.0 and kin.lower[4] == pytest.approx(-3.1416)  # panda_joint4
    assert kin.velocity_limits[0] == pytest.approx(0.3) and kin.velocity_limits[1] == pytest.approx(2.175)
    assert 1.0 < kin.reach < 1.2  # link offsets from joint 1 to the grasp target: about 1.09 m


def test_forward_kinematics_agrees_with_pybullet(kin: ArmKinematics, urdf: str, client: int, tmp_path: Path) -> None:
    path = tmp_path / "lift_panda.urdf"
    path.write_text(urdf)
    body = p.loadURDF(str(path), useFixedBase=True, physicsClientId=client)
    joint_index, link_index = {}, {}
    for index in range(p.getNumJoints(body, physicsClientId=client)):
        info = p.getJointInfo(body, index, physicsClientId=client)
        joint_index[info[1].decode()] = index
        link_index[info[12].decode()] = index
    for q in random_configurations(kin, 20, seed=1):
        for name, value in zip(JOINTS, q, strict=True):
            p.resetJointState(body, joint_index[name], value, physicsClientId=client)
        state = p.getLinkState(body, link_index[TCP], computeForwardKinematics=True, physicsClientId=client)
        position = np.array(state[4])
        rotation = np.array(p.getMatrixFromQuaternion(state[5])).reshape(3, 3)
        pose = kin.forward(q)
        assert np.linalg.norm(pose[:3, 3] - position) < 1e-4
        assert rotation_angle(pose[:3, :3], rotation) < 1e-4


def test_jacobian_matches_finite_differences(kin: ArmKinematics) -> None:
    q = random_configurations(kin, 1, seed=2)[0]
    jacobian = kin.jacobian(q)
    assert jacobian.shape == (6, kin.dof)
    pose, h = kin.forward(q), 1e-6
    for i in range(kin.dof):
        moved = q.copy()
        moved[i] += h
        other = kin.forward(moved)
        linear = (other[:3, 3] - pose[:3, 3]) / h
        skew = (other[:3, :3] @ pose[:3, :3].T - np.eye(3)) / h
        angular = np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
        np.testing.assert_allclose(jacobian[:3, i], linear, atol=1e-5)
        np.testing.assert_allclose(jacobian[3:, i], angular, atol=1e-5)


def test_ik_reaches_reachable_poses(kin: ArmKinematics) -> None:
    rng = np.random.default_rng(3)
    targets = [kin.forward(q) for q in random_configurations(kin, 50, seed=4)]
    results = [solve_ik(kin, target, kin.home(), rng) for target in targets]
    assert sum(r.success for r in results) / len(results) >= 0.95
    for target, result in zip(targets, results, strict=True):
        assert kin.within_limits(result.q)
        if result.success:
            reached = kin.forward(result.q)  # checked independently of the solver's own report
            assert np.linalg.norm(reached[:3, 3] - target[:3, 3]) < 1e-3
            assert rotation_angle(reached[:3, :3], target[:3, :3]) < 0.01
            assert result.position_error < 1e-3 and result.orientation_error < 0.01
            assert result.reason == ""


def test_ik_is_reproducible_with_the_same_seed(kin: ArmKinematics) -> None:
    target = kin.forward(random_configurations(kin, 1, seed=5)[0])
    start = kin.upper - 1e-3  # far from the target, to make restarts likely
    first = solve_ik(kin, target, start, np.random.default_rng(7))
    second = solve_ik(kin, target, start, np.random.default_rng(7))
    assert first.success and first.restarts >= 1  # the seeded generator was used
    np.testing.assert_array_equal(first.q, second.q)
    assert first.restarts == second.restarts


def test_ik_position_only_and_free_tool_axis(kin: ArmKinematics) -> None:
    rng = np.random.default_rng(6)
    spin = np.eye(4)
    spin[:3, :3] = [[math.cos(1.0), -math.sin(1.0), 0], [math.sin(1.0), math.cos(1.0), 0], [0, 0, 1]]
    for q in random_configurations(kin, 10, seed=8):
        target = kin.forward(q) @ spin  # same position and tool axis, turned 1 rad about that axis
        for mode in ("position", "axis"):
            result = solve_ik(kin, target, kin.home(), rng, mode=mode)
            assert result.success, result.reason
            reached = kin.forward(result.q)
            assert np.linalg.norm(reached[:3, 3] - target[:3, 3]) < 1e-3
            if mode == "axis":
                assert np.dot(reached[:3, 2], target[:3, 2]) > math.cos(0.01)


def test_ik_reports_a_target_beyond_reach(kin: ArmKinematics) -> None:
    target = np.eye(4)
    target[:3, 3] = [3.0, 0.0, 0.8]
    result = solve_ik(kin, target, kin.home(), np.random.default_rng(0))
    assert not result.success
    assert "from the shoulder, beyond the arm's 1.09 m reach" in result.reason
    assert result.reason.startswith("target 2.8")
    assert kin.within_limits(result.q)
    assert result.position_error > 1.5


def test_ik_reports_a_pose_it_cannot_reach(kin: ArmKinematics) -> None:
    target = np.eye(4)  # within arm's length of the shoulder, but the gripper would point up
    target[:3, 3] = [1.0, 0.0, 0.75]
    result = solve_ik(kin, target, kin.home(), np.random.default_rng(0), max_restarts=3)
    assert not result.success
    assert result.reason.startswith("did not converge: best error ")
    assert result.reason.endswith("°") and " cm / " in result.reason
    assert result.restarts == 3
    assert kin.within_limits(result.q)


def test_bad_inputs_are_named(urdf: str, kin: ArmKinematics) -> None:
    with pytest.raises(ValueError, match="'elbow' is not a joint"):
        ArmKinematics(urdf, ["lift_joint", "elbow"], TCP)
    with pytest.raises(ValueError, match="tcp_frame"):
        ArmKinematics(urdf, JOINTS, "no_such_link")
    with pytest.raises(ValueError, match="repeat"):
        ArmKinematics(urdf, ["lift_joint", "lift_joint"], TCP)
    with pytest.raises(ValueError, match="target_pose: expected a 4×4"):
        solve_ik(kin, np.eye(3), kin.home())
    with pytest.raises(ValueError, match="not a rotation"):
        solve_ik(kin, np.diag([2.0, 1.0, 1.0, 1.0]), kin.home())
    with pytest.raises(ValueError, match=r"q_seed: expected shape \(8,\)"):
        solve_ik(kin, np.eye(4), np.zeros(7))
    with pytest.raises(ValueError, match="mode"):
        solve_ik(kin, np.eye(4), kin.home(), mode="wrist")  # type: ignore[arg-type]


def test_fixed_joints_hold_their_values(urdf: str) -> None:
    open_hand = ArmKinematics(urdf, JOINTS, "panda_leftfinger", fixed={"panda_finger_joint1": 0.04})
    closed_hand = ArmKinematics(urdf, JOINTS, "panda_leftfinger")
    q = open_hand.home()
    gap = open_hand.forward(q)[:3, 3] - closed_hand.forward(q)[:3, 3]
    assert np.linalg.norm(gap) == pytest.approx(0.04)
    with pytest.raises(ValueError, match="fixed"):
        ArmKinematics(urdf, JOINTS, TCP, fixed={"lift_joint": 0.1})


DRAWER_START = np.array([0.3, 0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])


def test_cartesian_line_stays_on_the_line(kin: ArmKinematics) -> None:
    start = kin.forward(DRAWER_START)
    end = start.copy()
    end[:3, 3] += [-0.3, 0.05, 0.0]  # pull a drawer 30 cm towards the robot
    poses = line_poses(start, end, max_step=0.01)
    assert len(poses) == 31  # 30.4 cm in steps of at most 1 cm
    path = plan_cartesian_path(kin, DRAWER_START, poses)
    assert path.success, path.reason
    assert path.q.shape == (32, kin.dof) and path.max_position_error < 0.002
    assert all(kin.within_limits(q) for q in path.q)
    np.testing.assert_allclose(kin.forward(path.q[-1])[:3, 3], end[:3, 3], atol=1e-3)
    direction = (end[:3, 3] - start[:3, 3]) / np.linalg.norm(end[:3, 3] - start[:3, 3])

    def off_line(q: np.ndarray) -> float:
        pose = kin.forward(q)
        offset = pose[:3, 3] - start[:3, 3]
        assert rotation_angle(pose[:3, :3], start[:3, :3]) < 0.02
        return float(np.linalg.norm(offset - (offset @ direction) * direction))

    between = [a + s * (b - a) for a, b in zip(path.q[:-1], path.q[1:], strict=True) for s in np.linspace(0, 1, 5)]
    assert max(off_line(q) for q in between) < 0.002
    # and so does the timed trajectory through the waypoints, passing them at speed
    trajectory = plan_trajectory(path.q, JointLimits(kin.velocity_limits, 4 * kin.velocity_limits,
                                                     40 * kin.velocity_limits), dt=0.02)
    assert max(off_line(q) for q in trajectory.positions) < 0.002


def test_cartesian_arc_follows_a_door(kin: ArmKinematics) -> None:
    start = kin.forward(DRAWER_START)
    hinge = start[:3, 3] + [0.0, 0.4, 0.0]  # door 40 cm wide, hinged on the left, opening towards the robot
    path = plan_cartesian_path(kin, DRAWER_START, arc_poses(start, hinge, [0, 0, 1], math.radians(-40)))
    assert path.success, path.reason
    for q in path.q:
        position = kin.forward(q)[:3, 3]
        assert abs(np.linalg.norm((position - hinge)[:2]) - 0.4) < 0.002
        assert abs(position[2] - hinge[2]) < 0.002


def test_cartesian_path_fails_clearly(kin: ArmKinematics) -> None:
    start = kin.forward(DRAWER_START)
    far = start.copy()
    far[:3, 3] += [-0.3, 0.0, 0.0]
    jump = plan_cartesian_path(kin, DRAWER_START, [far])
    assert not jump.success and jump.failed_index == 0
    assert "to jump" in jump.reason and "from the previous waypoint" in jump.reason
    assert jump.q.shape == (1, kin.dof)
    away = start.copy()
    away[:3, 3] = [3.0, 0.0, 0.8]
    poses = line_poses(start, far, max_step=0.02)[:3] + [away]
    unreachable = plan_cartesian_path(kin, DRAWER_START, poses)
    assert not unreachable.success and unreachable.failed_index == 3
    assert unreachable.reason.startswith("pose 3 is unreachable: target ")
    assert unreachable.q.shape == (4, kin.dof)
    with pytest.raises(ValueError, match="start_q"):
        plan_cartesian_path(kin, kin.upper + 1.0, [far])


def test_bench_arm_reports_its_fields(urdf: str) -> None:
    report = bench_arm(urdf, JOINTS, TCP, n=4, seed=0)
    for key in ("ik_ms_median", "ik_ms_p95", "ik_success_rate", "trajectory_ms_median", "trajectory_ms_p95"):
        assert key in report and math.isfinite(report[key])
    assert report["n"] == 4 and report["dof"] == 8
    assert 0.0 <= report["ik_success_rate"] <= 1.0
