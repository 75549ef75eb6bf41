"""Shared fixtures: a PyBullet client, and a world served over real Zenoh on loopback."""

from __future__ import annotations

import threading
import uuid
from collections.abc import Iterator

import pybullet as p
import pytest
import zenoh

from agent.bus.keys import Keys
from agent.bus.liveness import LivenessWatch
from agent.bus.session import free_tcp_endpoint, open_session
from worlds.server import WorldServer


@pytest.fixture
def client() -> Iterator[int]:
    """A PyBullet DIRECT client with gravity, disconnected afterwards."""
    cid = p.connect(p.DIRECT)
    p.setGravity(0.0, 0.0, -9.81, physicsClientId=cid)
    yield cid
    p.disconnect(cid)


@pytest.fixture
def world() -> Iterator[tuple[zenoh.Session, Keys]]:
    """A `WorldServer` serving in a background thread on its own session; yields (client session, keys).

    The fixture returns only once the world's liveliness token is visible from the client, so the
    first query already finds the queryables. Nothing is reset: tests send their own reset.
    """
    endpoint = free_tcp_endpoint()
    keys = Keys(f"homebot/test-{uuid.uuid4().hex[:8]}")
    server_session = open_session(listen=[endpoint])
    stop = threading.Event()
    thread = threading.Thread(target=WorldServer(server_session, keys.namespace).serve, args=(stop,), daemon=True)
    thread.start()
    client = open_session(connect=[endpoint])
    watch = LivenessWatch(client, keys.world_alive)
    try:
        assert watch.wait_alive(10.0), "the world never declared its liveliness token"
        yield client, keys
    finally:
        watch.close()
        stop.set()
        thread.join(10.0)
        client.close()
        server_session.close()
