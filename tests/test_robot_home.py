"""The robot's start pose (``home``) is set by its first look, and nothing acts before it."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from agent.acsg.interfaces import SkillCall
from agent.perception.instances import Instance
from agent.pose import Pose2D
from skills.arm.skill_plan import SkillPlanError
from skills.robot import Robot, RobotConfig
from worlds.bus.codec import Message, decode, encode

H, W = 48, 64


class NoWorld:
    """A link whose every call fails the test: nothing may reach the world."""

    def call(self, name: str, meta: dict[str, Any]) -> Message:
        raise AssertionError(f"the world was asked {name} {meta}")


class EmptyView:
    """A link that answers observe with a frame of nothing, taken from ``base_pose``."""

    def __init__(self, base_pose: list[float]) -> None:
        self.base_pose = base_pose
        self.calls: list[str] = []

    def call(self, name: str, meta: dict[str, Any]) -> Message:
        self.calls.append(name)
        assert name == "observe", name
        reply = {"camera": {"width": W, "height": H, "fx": 32.0, "fy": 32.0, "cx": 32.0, "cy": 24.0},
                 "camera_pose": np.eye(4).tolist(), "base_pose": self.base_pose, "labels": []}
        arrays = {"rgb": np.zeros((H, W, 3), np.uint8), "depth": np.zeros((H, W), np.float32),
                  "seg": np.full((H, W), -1, dtype=np.int32)}
        return decode(encode(reply, arrays))


def _thing(key: int, label: str) -> Instance:
    return Instance(key, label, None, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int32), 0.01, 0, 0)


def test_opening_a_part_before_the_first_look_raises_without_asking_the_world() -> None:
    robot = Robot(NoWorld())  # type: ignore[arg-type]
    drawer, handle = _thing(0, "drawer"), _thing(1, "handle")
    drawer.children.append(handle.id)
    handle.parent = drawer.id
    robot.memory.instances.update({0: drawer, 1: handle})
    with pytest.raises(SkillPlanError, match="the robot has not looked yet"):
        robot.parts.open_part(drawer)
    result = robot.execute(SkillCall("open_drawer", "open:0", "o0", "0", {}))
    assert not result.ok and "the robot has not looked yet" in result.reason
    assert robot.home is None and robot.skill_times == []


def test_picking_away_before_the_first_look_fails_without_asking_the_world() -> None:
    robot = Robot(NoWorld())  # type: ignore[arg-type]
    robot.memory.instances[0] = _thing(0, "cup")
    result = robot.execute(SkillCall("pick_away", "pick_away:0", "o0", "0", {}))
    assert not result.ok and "the robot has not looked yet" in result.reason


def test_the_first_look_makes_where_the_robot_stands_its_home() -> None:
    link = EmptyView([1.0, 2.0, 0.5])
    robot = Robot(link, RobotConfig(see_table_edge=False))  # type: ignore[arg-type]
    assert robot.home is None
    robot.observe()
    assert link.calls == ["observe"]
    assert robot.home == robot.pose == Pose2D(1.0, 2.0, 0.5)
    assert isinstance(robot.home, Pose2D)
