"""What the robot's cameras see: a frame rendered without the robot's own body, its labels telling
what the camera shows of each thing now (a switch's state, an open door, the storage around a thing).
"""

from __future__ import annotations

from dataclasses import replace

from worlds.body import RobotBody
from worlds.camera import Frame, render, render_at
from worlds.facts import CLOSED_SHARE
from worlds.robot import CameraConfig
from worlds.robot_arm import CAMERAS, WRIST_CAMERA_FRAME
from worlds.scene_state import part_states
from worlds.stage import Stage
from worlds.things import Furniture, Label

Joints = dict[int, dict[str, float]]


def observe(stage: Stage, body: RobotBody, camera: str, head: CameraConfig, wrist: CameraConfig) -> Frame:
    """Render the head or the wrist camera, with the robot's own body stepped out of the picture
    meanwhile (what the hand holds stays in it).

    Args:
        stage: the built scene.
        body: the robot, which is back where it stood afterwards.
        camera: ``"head"`` or ``"wrist"`` (`CAMERAS`).
        head: the head camera's settings.
        wrist: the wrist camera's settings.

    Returns:
        The frame, each label with `visible_facts`.

    Raises:
        ValueError: when ``camera`` is neither.
    """
    if camera not in CAMERAS:
        raise ValueError(f"camera: {camera!r} is not one of {CAMERAS}")
    wrist_pose = body.arm.link_pose(WRIST_CAMERA_FRAME) if camera == "wrist" else None
    with body.out_of_sight() as pose:
        if wrist_pose is None:
            frame = render(stage.client, head, pose, stage.built.labels)
        else:
            frame = render_at(stage.client, wrist, wrist_pose, stage.built.labels)
    joints = part_states(stage)
    in_frame = {label["id"] for label in frame.labels}
    return replace(frame, labels=[visible_facts(stage, label, joints, in_frame) for label in frame.labels])


def visible_facts(stage: Stage, label: Label, joints: Joints, in_frame: set[int]) -> Label:
    """The label with what the camera shows of the thing now: a switch's ``state``, whether a
    storage piece or one of its doors and drawers stands open, and the kind of storage it is
    seen ``inside``. Doors may have moved since the home was built.

    ``inside`` is only given when the frame shows the storage's interior around the thing: the
    part that opens its slot stands open (past `CLOSED_SHARE` of its travel) and the piece
    itself, its carcass or that open part, is in the same frame. A carton glimpsed with no fridge
    in view, or behind a door shut since, is just a carton: a camera cannot tell it is in a fridge.

    Args:
        stage: the built scene.
        label: a label of the frame.
        joints: every storage part's joint value now (`worlds.scene_state.part_states`).
        in_frame: the instance ids the frame shows.

    Returns:
        ``label`` with ``state`` and ``inside`` added where the frame shows them.
    """
    facts, thing_id = stage.facts, label["id"]
    if facts is None:  # a tabletop: only its storage has a state
        piece = stage.built.storage.get(thing_id)
        if piece is None:
            return label
        parts = piece.placement.model.parts
        opened = any(joints[thing_id][q.name] > q.lower + CLOSED_SHARE * (q.upper - q.lower) for q in parts)
        return {**label, "state": "open" if opened else "closed"}
    extra: dict[str, str] = {}
    furniture = facts.furniture.get(thing_id)
    item = facts.items.get(thing_id)
    switches = (furniture or item).state if (furniture or item) is not None else {}
    if switches:
        extra["state"] = next(iter(switches.values()))
    if furniture is not None and furniture.storage is not None:
        extra["state"] = "open" if facts.is_open(furniture, joints=joints[thing_id]) else "closed"
    part = stage.parts.get(thing_id)
    if part is not None:  # a door or drawer: whether it stands open shows
        piece = facts.furniture[part[0]]
        extra["state"] = "open" if facts.is_open(piece, part[1], joints=joints[part[0]]) else "closed"
    access = facts.access_of(item) if item is not None else None
    if access is not None and _interior_in_view(stage, *access, joints, in_frame):
        extra["inside"] = access[0].category
    return {**label, **extra}


def _interior_in_view(stage: Stage, storage: Furniture, part_name: str, joints: Joints, in_frame: set[int]) -> bool:
    """Whether a frame with the ids ``in_frame`` shows the inside of ``storage`` behind
    ``part_name``: that part open now, and the carcass or the part in the frame."""
    assert stage.facts is not None
    piece = stage.built.storage[storage.instance_id]
    part_id = piece.placement.part_ids()[part_name]
    opened = stage.facts.is_open(storage, part_name, joints=joints[storage.instance_id])
    return opened and bool(in_frame & {storage.instance_id, part_id})
