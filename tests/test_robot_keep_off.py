"""What the arm keeps off while it works a door or drawer: everything remembered but the piece the
part belongs to, its parts and handles, what stands in it, and the table under it all."""

from __future__ import annotations

from typing import Any

import numpy as np

from agent.perception.instances import Instance
from agent.perception.voxels import keys_of
from skills.arm.clearance import box_points
from skills.robot import Robot
from worlds.bus.codec import Message


class NoWorld:
    """A link whose every call fails the test: nothing may reach the world."""

    def call(self, name: str, meta: dict[str, Any]) -> Message:
        raise AssertionError(f"the world was asked {name} {meta}")


def _remember(robot: Robot, label: str, centre: tuple[float, float, float], size: tuple[float, float, float],
              parent: Instance | None = None) -> Instance:
    keys, hits = keys_of(box_points(np.array(centre), np.array(size), step_m=0.01), 0.01)
    inst = Instance(len(robot.memory.instances), label, None, keys, hits, 0.01, 0, 0)
    robot.memory.instances[inst.id] = inst
    if parent is not None:
        inst.parent = parent.id
        parent.children.append(inst.id)
    return inst


def test_a_drawer_keeps_the_arm_off_its_neighbours_but_not_off_its_own_chest_and_what_it_holds() -> None:
    robot = Robot(NoWorld())  # type: ignore[arg-type]
    _remember(robot, "table", (0.0, 0.3, 0.745), (1.2, 0.8, 0.02))
    chest = _remember(robot, "drawer_chest", (0.0, 0.4, 0.9), (0.4, 0.3, 0.3))
    drawer = _remember(robot, "drawer", (0.0, 0.1, 0.82), (0.36, 0.3, 0.1), chest)  # pulled 0.15 m out
    handle = _remember(robot, "handle", (0.0, -0.06, 0.82), (0.1, 0.02, 0.02), drawer)
    other = _remember(robot, "drawer", (0.0, 0.25, 0.95), (0.36, 0.02, 0.1), chest)
    other_handle = _remember(robot, "handle", (0.0, 0.23, 0.95), (0.1, 0.02, 0.02), other)
    mug = _remember(robot, "mug", (0.05, 0.05, 0.87), (0.08, 0.08, 0.1))  # in the open drawer, over its front
    box = _remember(robot, "box", (0.35, -0.2, 0.8), (0.12, 0.12, 0.1))  # standing before the chest, aside
    near = robot.parts.keep_off(drawer)["keep_off"]
    assert len(near) == len(box.points())
    assert np.all(near[:, 0] > 0.28) and np.all(near[:, 1] < -0.13)  # the box's points, and only they
    # the drawer above: its chest left out too, but what stands in the open drawer below, outside
    # the chest and not in this drawer, is in the way
    assert len(robot.parts.keep_off(other)["keep_off"]) == len(box.points()) + len(mug.points())
    # the drawer itself and every handle of its chest, where they stand now, for the free move to
    # the handle; not the chest's body, nor the drawer above, nor what stands about
    own = robot.parts.keep_off(drawer)["part_points"]
    assert len(own) == len(drawer.points()) + len(handle.points()) + len(other_handle.points())
