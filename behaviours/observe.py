"""Observe: take one RGB-D frame from the world's head camera."""

from __future__ import annotations

from py_trees.common import Access, Status

from behaviours import blackboard as bb
from worlds.bus.codec import Message
from agent.observation import Observation, ObservationError
from agent.timing import StageTimer
from worlds.bus.link import WorldLink
from behaviours.world_command import WorldCommand


class Observe(WorldCommand):
    """Asks the world for a frame and puts the checked `Observation` on the blackboard.

    Args:
        link: the world link.
        timer: times the observation, if given.
        name: the node's name.
    """

    def __init__(self, link: WorldLink, timer: StageTimer | None = None, name: str = "Observe") -> None:
        super().__init__(name, link, "observe")
        self.timer = timer
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.OBSERVATION, access=Access.WRITE)

    def on_reply(self, message: Message) -> Status:
        try:
            observation = Observation.from_message(message)
        except ObservationError as error:
            self.feedback_message = str(error)
            return Status.FAILURE
        if self.timer is not None:
            round_trip_ms = self._pending.elapsed_s * 1000.0 if self._pending else 0.0
            self.timer.record("render", observation.render_ms)
            self.timer.record("transport", max(0.0, round_trip_ms - observation.render_ms))
        self.blackboard.set(bb.OBSERVATION, observation)
        x, y, yaw = observation.base_pose
        self.feedback_message = f"frame at ({x:.2f}, {y:.2f}), {len(observation.labels)} instances in view"
        return Status.SUCCESS


