"""The end stops of the scene's drawers and doors in PyBullet.

PyBullet's joint limits give way to whatever presses on them: the grip on a handle, the arm's
links, or a carried thing, which the world moves whatever the force. A drawer pushed shut by the
hand holding its handle (`worlds.arm.GRIP_FORCE`) went 17 mm past its closed end, and let go of
there it sprang back out to 10 mm open, counted open (occlusion 1031 and 1065 of tuning-wide); a
box carried into a closed cabinet door pushed it 0.38 rad in through its closed end (recursive
1259). A real end stop holds, and what presses the part against it is held back: `EndStops.hold`,
run after every physics step, puts every part pressed past its limits back within them, at rest.
"""

from __future__ import annotations

from collections.abc import Iterable

import pybullet as p


def _limited(body: int, links: Iterable[int], client: int) -> list[tuple[int, float, float]]:
    """(link, lower, upper) of each of ``links`` that moves on a limited joint (a drawer, a door)."""
    stops = []
    for link in links:
        info = p.getJointInfo(body, link, physicsClientId=client)
        if info[2] in (p.JOINT_PRISMATIC, p.JOINT_REVOLUTE) and info[8] <= info[9]:
            stops.append((link, float(info[8]), float(info[9])))
    return stops


class EndStops:
    """The joint limits held as end stops, of every body added.

    Args:
        client: the PyBullet client the bodies live in.
    """

    def __init__(self, client: int) -> None:
        self.client = client
        self._stops: dict[int, tuple[list[int], list[float], list[float]]] = {}  # body -> links, lowers, uppers

    def add(self, body: int) -> None:
        """Hold the joint limits of ``body``'s drawers and doors as end stops from now on.

        Args:
            body: an articulated body of the scene (a storage piece).
        """
        links = range(p.getNumJoints(body, physicsClientId=self.client))
        if stops := _limited(body, links, self.client):
            limited, lowers, uppers = (list(column) for column in zip(*stops))
            self._stops[body] = (limited, lowers, uppers)

    def hold(self) -> None:
        """Put every part pressed past its joint's limits back within them, at rest there."""
        for body, (links, lowers, uppers) in self._stops.items():
            states = p.getJointStates(body, links, physicsClientId=self.client)
            for link, lower, upper, state in zip(links, lowers, uppers, states):
                if not lower <= state[0] <= upper:
                    p.resetJointState(body, link, min(max(state[0], lower), upper), 0.0,
                                      physicsClientId=self.client)
