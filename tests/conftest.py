"""Shared fixtures: a PyBullet client, a world served over real Zenoh on loopback, one torch thread."""

from __future__ import annotations

from collections.abc import Iterator

import pybullet as p
import pytest
import zenoh

from worlds.bus.keys import Keys
from agent.app.runtime.local_world import local_world


@pytest.fixture
def client() -> Iterator[int]:
    """A PyBullet DIRECT client with gravity, disconnected afterwards."""
    cid = p.connect(p.DIRECT)
    p.setGravity(0.0, 0.0, -9.81, physicsClientId=cid)
    yield cid
    p.disconnect(cid)


@pytest.fixture
def world() -> Iterator[tuple[zenoh.Session, Keys]]:
    """A world served in a background thread over real Zenoh on loopback (`local_world`); yields
    (client session, keys) once the world's liveliness token is visible. Tests send their own reset."""
    with local_world() as served:
        yield served.session, served.keys


@pytest.fixture(scope="module")
def one_torch_thread() -> Iterator[None]:
    """Torch on one thread: tests share two cores with other work, where its extra threads only wait
    on each other."""
    import torch

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)
