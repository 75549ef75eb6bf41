"""Navigate: drive the planned path; the world stops at the first contact and says so.

The route the world says it drove (its reply's ``driven``) goes onto the trajectory corner by
corner, so a picture of the run follows the base around walls instead of cutting through them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from py_trees.common import Access, Status

from behaviours import blackboard as bb
from worlds.bus.codec import Message
from worlds.bus.link import WorldLink
from behaviours.world_command import WorldCommand
from agent.pose import Pose2D
from agent.timing import StageTimer


class Navigate(WorldCommand):
    """Drives the planned path; the world stops at the first contact, and the map marks where the base drove and bumped.

    Args:
        link: the world link.
        timeout_s: how long a move may take.
        timer: times each move's round trip (``drive``: the world driving the base, and the wire), if given.
        name: the node's name.
    """

    def __init__(self, link: WorldLink, timeout_s: float = 30.0, timer: StageTimer | None = None,
                 name: str = "Navigate") -> None:
        super().__init__(name, link, "move_base", timeout_s)
        self.timer = timer
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.PLAN, access=Access.READ)
        self.blackboard.register_key(bb.TRAJECTORY, access=Access.WRITE)
        self.blackboard.register_key(bb.MAP, access=Access.WRITE)  # marks where it drove and bumped
        self.blackboard.register_key(bb.FRONTIER_GOAL, access=Access.WRITE)

    def request(self) -> dict[str, Any]:
        plan = self.blackboard.get(bb.PLAN)
        if plan is None:
            raise ValueError("there is no plan to follow")
        return {"path": plan.path_xy.round(3).tolist(), "yaw": round(float(plan.yaw), 4)}

    def on_reply(self, message: Message) -> Status:
        if self.timer is not None and self._pending is not None:
            self.timer.record("drive", self._pending.elapsed_s * 1000.0)
        pose = message.meta.get("base_pose")
        if not (isinstance(pose, list) and len(pose) == 3):
            self.feedback_message = "move_base reply: base_pose must be [x, y, yaw]"
            return Status.FAILURE
        trajectory = self.blackboard.get(bb.TRAJECTORY)
        corners = _corners(message.meta.get("driven"), trajectory[-1][2] if trajectory else float(pose[2]))
        route = [trajectory[-1], *corners, pose] if trajectory else [*corners, pose]
        self.blackboard.get(bb.MAP).mark_driven(np.array([(float(p[0]), float(p[1])) for p in route]))
        trajectory.extend(corners)
        trajectory.append(Pose2D.of(pose))
        contact = message.meta.get("contact")
        if contact:  # the way to the frontier is blocked: choose afresh rather than push on
            self.blackboard.set(bb.FRONTIER_GOAL, None)
        travelled = float(message.meta.get("travelled_m", 0.0))
        point = message.meta.get("contact_point")
        if isinstance(point, list) and len(point) == 2:
            self.blackboard.get(bb.MAP).mark_contact((float(point[0]), float(point[1])))
        if contact:
            self.feedback_message = f"stopped after {travelled:.2f} m at contact with {contact.get('category', 'something')}"
        else:
            self.feedback_message = f"moved {travelled:.2f} m to ({pose[0]:.2f}, {pose[1]:.2f})"
        return Status.SUCCESS


def _corners(driven: Any, heading: float) -> list[Pose2D]:
    """The inner points of a move_base reply's ``driven`` route, as poses at the heading the base
    drove with (it turns only at the end). Its first point is where the base stood, already on the
    trajectory; its last is the reply's ``base_pose``. A malformed route adds nothing."""
    if not (isinstance(driven, list) and all(isinstance(p, list) and len(p) == 2 for p in driven)):
        return []
    return [Pose2D(float(x), float(y), heading) for x, y in driven[1:-1]]
