"""Navigate: drive the planned path; the world stops at the first contact and says so."""

from __future__ import annotations

from typing import Any

from py_trees.common import Access, Status

from agent import blackboard as bb
from agent.bus.codec import Message
from agent.runtime.world_link import WorldLink
from behaviours.world_command import WorldCommand


class Navigate(WorldCommand):
    def __init__(self, link: WorldLink, timeout_s: float = 30.0, name: str = "Navigate") -> None:
        super().__init__(name, link, "move_base", timeout_s)
        self.blackboard = self.attach_blackboard_client(name=name)
        self.blackboard.register_key(bb.PLAN, access=Access.READ)
        self.blackboard.register_key(bb.TRAJECTORY, access=Access.WRITE)
        self.blackboard.register_key(bb.MAP, access=Access.READ)

    def request(self) -> dict[str, Any]:
        plan = self.blackboard.get(bb.PLAN)
        if plan is None:
            raise ValueError("there is no plan to follow")
        return {"path": plan.path_xy.round(3).tolist(), "yaw": round(float(plan.yaw), 4)}

    def on_reply(self, message: Message) -> Status:
        pose = message.meta.get("base_pose")
        if not (isinstance(pose, list) and len(pose) == 3):
            self.feedback_message = "move_base reply: base_pose must be [x, y, yaw]"
            return Status.FAILURE
        trajectory = self.blackboard.get(bb.TRAJECTORY)
        trajectory.append(tuple(float(v) for v in pose))
        contact = message.meta.get("contact")
        travelled = float(message.meta.get("travelled_m", 0.0))
        point = message.meta.get("contact_point")
        if isinstance(point, list) and len(point) == 2:
            self.blackboard.get(bb.MAP).mark_contact((float(point[0]), float(point[1])))
        if contact:
            self.feedback_message = f"stopped after {travelled:.2f} m at contact with {contact.get('category', 'something')}"
        else:
            self.feedback_message = f"moved {travelled:.2f} m to ({pose[0]:.2f}, {pose[1]:.2f})"
        return Status.SUCCESS
