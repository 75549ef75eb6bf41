"""A world served from a thread of this process, reached over real Zenoh on loopback.

The agent's side talks to it through the bus exactly as to a world process; the process that
started it may also read the `World` itself between commands (an evaluation measuring where things
ended up, against the ground truth the agent never sees). Tests use it for the same reason.
"""

from __future__ import annotations

import threading
import uuid
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass

import zenoh

from worlds.bus.keys import Keys
from worlds.bus.liveness import LivenessWatch
from worlds.bus.session import free_tcp_endpoint, open_session
from worlds.server import WorldServer
from worlds.sim import World


class LocalWorldError(RuntimeError):
    """The world thread never became reachable."""


@dataclass(frozen=True)
class LocalWorld:
    session: zenoh.Session  # the agent's session, connected to the world's
    keys: Keys
    server: WorldServer

    @property
    def world(self) -> World:
        """The simulated world: read it only while no command is in flight."""
        world = self.server.world
        if world is None:
            raise LocalWorldError("the local world has stopped")
        return world


@contextmanager
def local_world(ready_timeout_s: float = 10.0, namespace: str | None = None) -> Iterator[LocalWorld]:
    """Serve a `WorldServer` on its own session in a daemon thread; yield once its liveliness token
    is visible from the agent's session, so the first query already finds the queryables. Nothing
    is reset: the caller sends its own reset.

    Args:
        ready_timeout_s: how long the world may take to become visible.
        namespace: the bus namespace (a fresh one when None).

    Yields:
        The agent's session, the keys and the server.

    Raises:
        LocalWorldError: the world never became visible.
    """
    endpoint = free_tcp_endpoint()
    keys = Keys(namespace or f"homebot/local-{uuid.uuid4().hex[:8]}")
    server_session = open_session(listen=[endpoint])
    stop = threading.Event()
    server = WorldServer(server_session, keys.namespace)
    thread = threading.Thread(target=server.serve, args=(stop,), name="local-world", daemon=True)
    thread.start()
    client = open_session(connect=[endpoint])
    watch = LivenessWatch(client, keys.world_alive)
    try:
        if not watch.wait_alive(ready_timeout_s):
            raise LocalWorldError(f"the local world declared no liveliness token within {ready_timeout_s:g} s")
        yield LocalWorld(client, keys, server)
    finally:
        watch.close()
        stop.set()
        thread.join(10.0)
        client.close()
        server_session.close()
