"""One camera frame as the agent receives it, checked at the edge.

The world's reply is validated here (shapes agree with the camera's size, the pose is a rigid
transform, every label names an instance in the frame) so nothing downstream handles a bad frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worlds.bus.codec import Message
from agent.mapping.camera import Intrinsics
from agent.pose import Pose2D


class ObservationError(ValueError):
    """A frame whose parts disagree; the text names the field."""


@dataclass(frozen=True)
class InstanceLabel:
    """What the camera can tell about one instance in view: what it is and looks like.

    ``state`` is a visible state (a lamp "on", a door "open"); ``inside`` names the kind of storage
    the instance sits in when the frame shows that storage's interior around it (a carton seen in
    an open fridge: "fridge"). Which room a thing stands in is no label: no camera sees a room's
    name, so the agent and the simulated VLM work it out from what stands in view
    (`agent.perception.rooms`).
    """

    id: int
    category: str
    colour: str
    state: str | None = None
    inside: str | None = None

    @classmethod
    def from_meta(cls, entry: dict) -> InstanceLabel:
        """A label read from an observation's metadata.

        Args:
            entry: one entry of the metadata's ``labels``.

        Returns:
            The label.
        """
        optional = {key: (str(entry[key]) if entry.get(key) is not None else None) for key in ("state", "inside")}
        return cls(int(entry["id"]), str(entry["category"]), str(entry["colour"]), **optional)


@dataclass(frozen=True)
class Observation:
    rgb: np.ndarray  # (H, W, 3) uint8
    depth: np.ndarray  # (H, W) float32, linear metres, 0 = no return
    segmentation: np.ndarray  # (H, W) int32 instance ids, -1 = nothing
    labels: tuple[InstanceLabel, ...]
    intrinsics: Intrinsics
    camera_to_world: np.ndarray  # (4, 4), OpenCV camera frame
    base_pose: Pose2D
    render_ms: float = 0.0

    @classmethod
    def from_message(cls, message: Message) -> Observation:
        """An observation read from the world's message, checked.

        Args:
            message: the observation's message (metadata and image arrays).

        Returns:
            The observation.

        Raises:
            ObservationError: a field is missing or malformed.
        """
        meta, arrays = message.meta, message.arrays
        try:
            intrinsics = Intrinsics.from_meta(meta["camera"])
            pose = np.asarray(meta["camera_pose"], dtype=float)
            base_pose = tuple(float(v) for v in meta["base_pose"])
            labels = tuple(InstanceLabel.from_meta(entry) for entry in meta["labels"])
            rgb, depth, seg = arrays["rgb"], arrays["depth"], arrays["seg"]
        except (KeyError, TypeError, ValueError) as error:
            raise ObservationError(f"observe reply: missing or malformed field ({error!r})") from None
        size = (intrinsics.height, intrinsics.width)
        for name, array, shape, dtype in (
            ("rgb", rgb, size + (3,), np.uint8),
            ("depth", depth, size, np.float32),
            ("seg", seg, size, np.int32),
        ):
            if array.shape != shape or array.dtype != dtype:
                raise ObservationError(
                    f"observe reply: {name} is {array.dtype}{list(array.shape)}, the camera says {np.dtype(dtype)}{list(shape)}"
                )
        if pose.shape != (4, 4) or not np.allclose(pose[:3, :3] @ pose[:3, :3].T, np.eye(3), atol=1e-4):
            raise ObservationError("observe reply: camera_pose must be a 4x4 rigid transform")
        if len(base_pose) != 3:
            raise ObservationError("observe reply: base_pose must be [x, y, yaw]")
        base_pose = Pose2D(*base_pose)
        present = set(np.unique(seg).tolist()) - {-1}
        named = {label.id for label in labels}
        if named != present:
            raise ObservationError(
                f"observe reply: labels name instances {sorted(named - present)} not in the frame "
                f"and miss {sorted(present - named)}"
            )
        return cls(rgb, depth, seg, labels, intrinsics, pose, base_pose, float(meta.get("render_ms", 0.0)))
