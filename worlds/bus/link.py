"""The agent's handle on one world: its session, its keys, and whether it is still alive."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import zenoh

from worlds.bus.codec import Message
from worlds.bus.keys import Keys
from worlds.bus.liveness import WorldWatch
from worlds.bus.rpc import Arrays, PendingReply


class WorldLink:
    """Sends world commands; any query fails at once with a reason when the world's token goes.

    ``liveness`` (a `WorldWatch`) follows the world: its token, and its process once the agent that
    started it says so (`follow_process`); it words why a query got no reply.

    Args:
        session: the bus session.
        keys: the namespace's keys.
        timeout_s: how long a reply may take by default.
    """

    def __init__(self, session: zenoh.Session, keys: Keys, timeout_s: float = 10.0) -> None:
        self.session = session
        self.keys = keys
        self.timeout_s = timeout_s
        self.liveness = WorldWatch(session, keys)

    def request(self, verb: str, meta: dict[str, Any] | None = None, timeout_s: float | None = None,
                arrays: Arrays | None = None, on_reply: Callable[[], None] | None = None) -> PendingReply:
        """Send the command ``verb`` (with ``arrays``, e.g. an arm trajectory's samples); poll the reply.

        Args:
            verb: the command's name.
            meta: its metadata.
            timeout_s: how long the reply may take (the link's default when None).
            arrays: its arrays.
            on_reply: called (from Zenoh's thread) once there is something to poll.

        Returns:
            The pending reply.
        """
        return PendingReply(self.session, self.keys.world_cmd(verb), meta, arrays,
                            timeout_s or self.timeout_s, self.liveness, on_reply=on_reply)

    def describe(self, timeout_s: float | None = None, on_reply: Callable[[], None] | None = None) -> PendingReply:
        """Ask for the robot's description (URDF, cameras, arm joints and limits).

        Args:
            timeout_s: how long the reply may take (the link's default when None).
            on_reply: called (from Zenoh's thread) once there is something to poll.

        Returns:
            The pending reply.
        """
        return PendingReply(self.session, self.keys.world_description, {}, None,
                            timeout_s or self.timeout_s, self.liveness, on_reply=on_reply)

    def call(self, verb: str, meta: dict[str, Any] | None = None, timeout_s: float | None = None,
             arrays: Arrays | None = None) -> Message:
        """Send the command ``verb`` and wait for its reply (for tools and tests, never inside a tree tick).

        Args:
            verb: the command's name.
            meta: its metadata.
            timeout_s: how long the reply may take (the link's default when None).
            arrays: its arrays.

        Returns:
            The reply.

        Raises:
            QueryFailed: no reply came, or the world is gone.
        """
        return self.request(verb, meta, timeout_s, arrays).wait()

    def follow_process(self, exit_code: Callable[[], int | None]) -> None:
        """Follow the world's process (one this agent started), to tell a world that is gone from
        one that stopped answering, and to say how it ended.

        Args:
            exit_code: the process's exit code, None while it runs (`subprocess.Popen.poll`).
        """
        self.liveness.follow_process(exit_code)

    def close(self) -> None:
        self.liveness.close()
