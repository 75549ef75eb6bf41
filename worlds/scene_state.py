"""What moves in a built scene: the joint values of storage parts, and where small objects are.

Storage parts are set here directly, or moved by the arm through physics (`worlds.manipulation`);
either way whatever stands in a drawer moves with it (`worlds.riders`).
"""

from __future__ import annotations

import math

import pybullet as p

from worlds.stage import Stage


def set_part_state(stage: Stage, furniture_id: int, part_name: str, value: float) -> None:
    """Set a door, drawer or flap of a storage piece at once; whatever stands in a drawer moves with it.

    Args:
        stage: the built scene.
        furniture_id: the storage piece's instance id.
        part_name: the part's name in its storage model.
        value: the joint value (rad or m), within the part's limits.

    Raises:
        ValueError: naming the argument that is not a storage piece, a part of it, or within its limits.
    """
    piece = stage.built.storage.get(furniture_id)
    if piece is None:
        raise ValueError(f"furniture_id: {furniture_id} is not a storage piece")
    model = piece.placement.model
    try:
        part = model.part(part_name)
    except KeyError as error:
        raise ValueError(f"part_name: {error.args[0]}") from None
    if not (math.isfinite(value) and part.lower <= value <= part.upper):
        raise ValueError(f"value: {value} is outside [{part.lower}, {part.upper}] for {part_name}")
    p.resetJointState(piece.body, piece.links[part_name], value, physicsClientId=stage.client)
    stage.riders.sync()


def object_position(stage: Stage, instance_id: int) -> tuple[float, float, float]:
    """Where a small object's centre is now.

    Args:
        stage: the built scene.
        instance_id: the object's instance id.

    Returns:
        Its centre (x, y, z) in the world.
    """
    position, _ = p.getBasePositionAndOrientation(stage.built.items[instance_id], physicsClientId=stage.client)
    return (float(position[0]), float(position[1]), float(position[2]))


def part_states(stage: Stage) -> dict[int, dict[str, float]]:
    """Every storage piece's parts' joint values now.

    Args:
        stage: the built scene.

    Returns:
        Furniture id -> part name -> joint value (rad or m).
    """
    return {
        furniture_id: {
            part.name: float(p.getJointState(piece.body, piece.links[part.name], physicsClientId=stage.client)[0])
            for part in piece.placement.model.parts
        }
        for furniture_id, piece in stage.built.storage.items()
    }
