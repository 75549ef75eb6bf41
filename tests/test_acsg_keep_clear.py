"""Where nothing is put down on a table: the sweeps of its doors and drawers and the lanes to their
handles (`agent.acsg.keep_clear`), read off a memory of a rendered drawer chest."""

from __future__ import annotations

import numpy as np
import pytest

from agent.acsg.keep_clear import LANE_LEAST_M, LANE_STEP_M, kept_clear, way_out
from agent.perception.memory import InstanceMemory
from agent.perception.part_geometry import handle_geometry
from agent.perception.part_motion import DEFAULT_AMOUNT, part_motion
from skills.arm.idle_space import idle_spot
from test_perception_scene import INTRINSICS, Box, Front, look_at, render, storage

EYE = np.array([0.0, -0.8, 1.45])


def _chest_memory() -> InstanceMemory:
    chest = storage(10, "drawer chest", (-0.2, 0.2), (0.23, 0.53), (0.75, 1.1),
                    (Front("drawer", (-0.198, 0.198), (0.77, 0.93)), Front("drawer", (-0.198, 0.198), (0.932, 1.08))))
    table = Box.at(1, "table", (0.0, 0.1, 0.73), (1.6, 0.9, 0.04))
    memory = InstanceMemory()
    pose = look_at(EYE, (0.0, 0.3, 0.9))
    depth, seg, labels = render([table, *chest], pose)
    memory.integrate_frame(depth, seg, labels, INTRINSICS, pose)
    return memory


def test_the_space_of_a_part_done_with_is_the_table_s_again() -> None:
    memory = _chest_memory()
    drawers = sorted((inst for inst in memory.with_label("drawer")), key=lambda inst: inst.centroid[2])
    assert len(drawers) == 2
    robot = np.array([0.0, -0.9])
    every = np.vstack(kept_clear(memory, EYE, robot))
    # a drawer sweeps out towards the robot, and its lane runs on to the robot
    assert every[:, 1].min() < 0.0 and every[:, 1].max() > 0.2
    lower_done = np.vstack(kept_clear(memory, EYE, robot, done_with={drawers[0].id}))
    both_done = kept_clear(memory, EYE, robot, done_with={d.id for d in drawers})
    assert 0 < len(lower_done) < len(every)
    assert both_done == []
    # what is left is the upper drawer's: its sweep and lane stand at its height, above the lower's top
    assert lower_done[:, 2].min() > 0.93 - 0.05


def test_a_thing_taken_out_of_storage_is_not_put_down_in_the_lane_it_came_out_along() -> None:
    # A box 18 cm across taken out of a cabinet at the table's far side (y = 0.3): put down just
    # before the cabinet, in its way out, it hid what it had covered from the robot and stood in
    # the way of the hand reaching in for it.
    xs, ys = np.meshgrid(np.arange(-0.6, 0.6, 0.01), np.arange(-0.4, 0.2, 0.01))
    table = np.column_stack([xs.ravel(), ys.ravel(), np.full(xs.size, 0.75)])
    stood, robot, radius = np.array([0.1, 0.3, 0.85]), np.array([0.1, -0.9]), 0.09
    lane = way_out(stood, radius, robot, 0.78)
    assert lane[:, 1].max() <= stood[1] + 1e-9 and lane[:, 1].min() > robot[1] - 0.05
    assert np.allclose(lane[:, 2], 0.78) and np.ptp(lane[:, 0]) == pytest.approx(2 * radius)
    near = (0.1, 0.05)  # before the cabinet, towards the robot
    assert abs(idle_spot(table, [], radius, near)[0] - 0.1) < 0.01  # in its way out, without the lane
    spot = idle_spot(table, [lane], radius, near)
    assert abs(spot[0] - 0.1) >= 2 * radius  # beside it, clear of it, with the lane
    assert len(way_out(stood, radius, stood[:2], 0.78)) == 0


@pytest.mark.parametrize("hinge", ["left", "right"])
def test_the_lane_to_an_open_door_s_handle_runs_the_way_the_handle_faces(hinge: str) -> None:
    # A door standing open turns its handle aside; the hand comes to it along the way it faces, and
    # a bottle put down 14 cm beside it there held the hand back from closing the door (occlusion
    # 1121 of tuning-wide). The lane runs that way, however the robot stands.
    cabinet = storage(10, "cabinet", (-0.2, 0.2), (0.23, 0.53), (0.75, 1.1),
                      (Front("door", (-0.198, 0.198), (0.77, 1.08), hinge=hinge),))
    table = Box.at(1, "table", (0.0, 0.1, 0.73), (1.6, 0.9, 0.04))
    memory = InstanceMemory()
    pose = look_at(EYE, (0.0, 0.3, 0.9))
    memory.integrate_frame(*render([table, *cabinet], pose), INTRINSICS, pose)
    handle, = memory.with_label("handle")
    geometry = handle_geometry(memory, handle.id, EYE, kind="door")
    motion = part_motion(geometry, DEFAULT_AMOUNT["door"])
    handle_open = motion[:3, :3] @ geometry.handle_point + motion[:3, 3]
    facing = motion[:3, :3] @ geometry.normal
    assert abs(facing[0]) > 0.8  # aside
    for robot in (np.array([0.0, -0.9]), handle_open[:2] - 1.0 * facing[:2]):  # before it; behind the handle
        kept = np.vstack(kept_clear(memory, EYE, robot))
        for out in (0.05, 0.1, LANE_LEAST_M - LANE_STEP_M):
            gap = np.linalg.norm(kept - (handle_open + out * facing), axis=1).min()
            assert gap < 0.04, (robot, out, gap)


def test_a_door_standing_open_keeps_clear_the_way_it_shuts() -> None:
    # The skill that opened the door carried its points along in the memory; swept on from there,
    # the way back to closed was left free, and a box out of the cabinet was put down in it: the
    # door stopped on it when it was closed (recursive 1227 of tuning-wide).
    cabinet = storage(10, "cabinet", (-0.2, 0.2), (0.23, 0.53), (0.75, 1.1),
                      (Front("door", (-0.198, 0.198), (0.77, 1.08), hinge="left"),))
    table = Box.at(1, "table", (0.0, 0.1, 0.73), (1.6, 0.9, 0.04))
    memory = InstanceMemory()
    pose = look_at(EYE, (0.0, 0.3, 0.9))
    memory.integrate_frame(*render([table, *cabinet], pose), INTRINSICS, pose)
    handle, = memory.with_label("handle")
    door = memory.get(handle.parent)
    geometry = handle_geometry(memory, handle.id, EYE, kind="door")
    opening = DEFAULT_AMOUNT["door"]
    memory.move(door.id, part_motion(geometry, opening))
    halfway = part_motion(geometry, opening / 2)
    on_the_way = halfway[:3, :3] @ geometry.handle_point + halfway[:3, 3]  # the handle, half shut

    def gap(kept: list[np.ndarray]) -> float:
        return float(np.linalg.norm(np.vstack(kept) - on_the_way, axis=1).min())

    robot = np.array([0.0, -0.9])
    assert gap(kept_clear(memory, EYE, robot, standing_open={door.id: (geometry, opening)})) < 0.03
    assert gap(kept_clear(memory, EYE, robot)) > 0.1  # read off where it stands open
