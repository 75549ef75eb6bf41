"""IntegrateMap: fuse the newest frame into the TSDF and refresh the 2D maps."""

from __future__ import annotations

import contextlib

import py_trees
from py_trees.common import Access, Status

from behaviours import blackboard as bb
from agent.timing import StageTimer


class IntegrateMap(py_trees.behaviour.Behaviour):
    """Fuses the newest frame into the TSDF and refreshes the 2D maps on the blackboard.

    Args:
        timer: times the fusion, if given.
        name: the node's name.
    """

    def __init__(self, timer: StageTimer | None = None, name: str = "IntegrateMap") -> None:
        super().__init__(name)
        self.timer = timer
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.OBSERVATION, access=Access.READ)
        self.blackboard.register_key(bb.MAP, access=Access.WRITE)  # fuses the frame into it

    def update(self) -> Status:
        observation = self.blackboard.get(bb.OBSERVATION)
        world_map = self.blackboard.get(bb.MAP)
        with self.timer.measure("tsdf") if self.timer else contextlib.nullcontext():
            world_map.integrate(observation.depth, observation.intrinsics, observation.camera_to_world,
                                observation.base_pose[:2])
        self.feedback_message = (
            f"free {world_map.free_area_m2():.1f} m², explored {world_map.explored.sum() * world_map.spec.resolution**2:.1f} m²"
        )
        return Status.SUCCESS
