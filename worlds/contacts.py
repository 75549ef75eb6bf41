"""What the robot touches where it stands: the deepest contact of its base, or of its arm and what
the hand carries, with anything but the floors.
"""

from __future__ import annotations

import pybullet as p

from worlds.body import RobotBody
from worlds.robot import ROBOT_HEIGHT, ROBOT_RADIUS
from worlds.stage import Stage
from worlds.things import Label

#: A contact: the label of what is touched and the (x, y) on it where the robot touches it.
Contact = tuple[Label, tuple[float, float]]


def base_contact(stage: Stage, body: RobotBody) -> Contact | None:
    """The deepest contact of the base's cylinder, ignoring floors.

    Args:
        stage: the built scene.
        body: the robot, where it stands.

    Returns:
        The label of what the base touches (a storage part's own) and the (x, y) of the contact on
        it; None when it touches nothing.
    """
    x, y, _ = body.pose
    lo, hi = (x - ROBOT_RADIUS, y - ROBOT_RADIUS, 0.0), (x + ROBOT_RADIUS, y + ROBOT_RADIUS, ROBOT_HEIGHT)
    deepest: tuple[float, tuple[int, int], tuple[float, float]] | None = None
    for other in {b for b, _ in p.getOverlappingObjects(lo, hi, physicsClientId=stage.client) or ()}:
        if other in body.bodies or other in stage.floors:
            continue
        for point in p.getClosestPoints(body.base, other, 0.0, physicsClientId=stage.client):
            if deepest is None or point[8] < deepest[0]:
                deepest = (point[8], (other, point[4]), (float(point[6][0]), float(point[6][1])))
    if deepest is None:
        return None
    return stage.label(*deepest[1]), deepest[2]


def arm_contact(stage: Stage, body: RobotBody) -> Contact | None:
    """Like `base_contact`, for the arm's links and what the hand carries (floors and the held thing
    aside).

    Args:
        stage: the built scene.
        body: the robot, where it stands.

    Returns:
        The label of what the arm or its load touches (`Stage.label_of`, naming a part) and the
        (x, y) of the deepest contact; None when they touch nothing.
    """
    arm, held = body.arm, body.arm.grip
    ours: list[tuple[int, int]] = [(body.robot, link) for link in arm.link_names]
    if held is not None and not held.tied:
        ours.append((held.body, -1))
    deepest: tuple[float, tuple[int, int], tuple[float, float]] | None = None
    for own, link in ours:
        lo, hi = p.getAABB(own, link, physicsClientId=stage.client)
        for other in {b for b, _ in p.getOverlappingObjects(lo, hi, physicsClientId=stage.client) or ()}:
            if other in (*body.bodies, own) or other in stage.floors or (held and other == held.body):
                continue
            for point in p.getClosestPoints(own, other, 0.0, linkIndexA=link, physicsClientId=stage.client):
                if deepest is None or point[8] < deepest[0]:
                    deepest = (point[8], (other, point[4]), (float(point[6][0]), float(point[6][1])))
    if deepest is None:
        return None
    return stage.label_of(*deepest[1]), deepest[2]
