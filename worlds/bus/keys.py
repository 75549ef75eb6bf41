"""Key expressions of the bus, all under one namespace per run (``homebot/<run-id>`` by default).

============================================  =====================================================
key                                           what travels there
============================================  =====================================================
``<ns>/world/cmd/<verb>``                     queryable: a command to the world, answered by a reply
``<ns>/world/robot/description``              queryable: the robot model and camera parameters
``<ns>/world/alive``                          liveliness token, present while the world serves
``<ns>/agent/tree``                           publication: a tree snapshot per tick (JSON)
``<ns>/agent/events``                         publication: episode events (JSON)
``<ns>/agent/control/<verb>``                 queryable: pause, step, breakpoints, faults (JSON)
============================================  =====================================================
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_NAMESPACE = re.compile(r"^[A-Za-z0-9_\-]+(/[A-Za-z0-9_\-]+)*$")

def check_namespace(namespace: str) -> str:
    """Return ``namespace`` if it is a plain key prefix (no wildcards, no empty chunks).

    Args:
        namespace: the namespace.

    Returns:
        The namespace.

    Raises:
        ValueError: it is not a plain key prefix.
    """
    if not _NAMESPACE.match(namespace):
        raise ValueError(
            f"namespace: {namespace!r} must be chunks of letters, digits, '_' or '-' joined by '/'"
        )
    return namespace


@dataclass(frozen=True)
class Keys:
    """The key expressions of one run."""

    namespace: str

    def __post_init__(self) -> None:
        check_namespace(self.namespace)

    def world_cmd(self, verb: str) -> str:
        """The key the world answers the command ``verb`` on.

        Args:
            verb: the command's name.

        Returns:
            The key.
        """
        return f"{self.namespace}/world/cmd/{verb}"

    @property
    def world_description(self) -> str:
        return f"{self.namespace}/world/robot/description"

    @property
    def world_alive(self) -> str:
        return f"{self.namespace}/world/alive"

    @property
    def agent_tree(self) -> str:
        return f"{self.namespace}/agent/tree"

    @property
    def agent_events(self) -> str:
        return f"{self.namespace}/agent/events"

    def agent_control(self, verb: str) -> str:
        """The key the agent answers the control request ``verb`` on (``*``: every verb).

        Args:
            verb: the request's name (``state``, ``pause``, ...), or ``*``.

        Returns:
            The key.
        """
        return f"{self.namespace}/agent/control/{verb}"


#: What `homebot watch` subscribes to when no namespace is given: every run's snapshots.
ANY_AGENT_TREE = "**/agent/tree"

#: What the inspector subscribes to when no namespace is given: every run's episode events.
ANY_AGENT_EVENTS = "**/agent/events"

#: Where a control client asks which agents answer when no namespace is given.
ANY_AGENT_CONTROL_STATE = "**/agent/control/state"


def control_namespace(key: str) -> str:
    """The namespace of a control key (``<ns>/agent/control/<verb>``).

    Args:
        key: the key.

    Returns:
        The namespace.

    Raises:
        ValueError: the key is not a control key.
    """
    namespace, marker, verb = key.rpartition("/agent/control/")
    if not marker or not verb or "/" in verb:
        raise ValueError(f"key: {key!r} is not <namespace>/agent/control/<verb>")
    return check_namespace(namespace)
