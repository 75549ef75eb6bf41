"""The robot base's pose on the floor, as one named type rather than a bare tuple of three floats.

`Pose2D` is a `NamedTuple`, so it unpacks, indexes and serialises (JSON writes it as a list) like
the ``(x, y, yaw)`` tuples the wire carries, while its fields say which number is which.
"""

from __future__ import annotations

from typing import Iterable, NamedTuple


class Pose2D(NamedTuple):
    """Where the base stands: ``x`` and ``y`` in metres in the world frame, ``yaw`` in radians
    counter-clockwise from +x."""

    x: float
    y: float
    yaw: float

    @classmethod
    def of(cls, values: Iterable[float]) -> Pose2D:
        """A pose from any three numbers (a wire list, a numpy array).

        Args:
            values: x, y and yaw, in that order.

        Returns:
            The pose, with plain Python floats.
        """
        x, y, yaw = (float(value) for value in values)
        return cls(x, y, yaw)
