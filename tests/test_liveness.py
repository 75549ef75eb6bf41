"""Why a query to the world got no reply, over real Zenoh on loopback: a server that goes is gone
(not a key nobody serves), a live one that does not answer in time is alive but silent, a namespace
no world serves names the worlds that are visible, a followed process tells a frozen world from a
dead one, and a closed port is connection refused."""

from __future__ import annotations

import time

import pytest

from worlds.bus.keys import Keys
from worlds.bus.liveness import WorldWatch, refused
from worlds.bus.rpc import CommandServer, PendingReply, QueryFailed, call
from worlds.bus.session import free_tcp_endpoint, open_session

from test_rpc import PROPAGATE_S, Bus, bus, echo  # noqa: F401 - the two sessions' fixture


def test_a_server_whose_session_closes_is_gone_not_unserved(bus: Bus) -> None:
    """A server that dies ends its queries and drops its token at the same moment, in either order:
    the query in flight fails as gone, not as a key nobody serves."""
    keys = Keys(bus.namespace)
    endpoint = free_tcp_endpoint()
    dying = open_session(listen=[endpoint])
    agent = open_session(connect=[endpoint])
    watch = WorldWatch(agent, keys)
    try:
        token = dying.liveliness().declare_token(keys.world_alive)  # noqa: F841 (dropped with the session)
        server = CommandServer(dying, bus.namespace)
        server.add(keys.world_cmd("observe"), echo)  # declared, never served
        assert watch.wait_alive(5.0)
        time.sleep(PROPAGATE_S)
        pending = PendingReply(agent, keys.world_cmd("observe"), timeout_s=60, watch=watch)
        assert pending.poll() is None
        dying.close()
        started = time.monotonic()
        with pytest.raises(QueryFailed, match=r"the world is gone from the bus \(its liveliness token .* was dropped"):
            pending.wait()
        assert time.monotonic() - started < 5
    finally:
        watch.close()
        agent.close()


def test_a_live_world_that_does_not_answer_in_time_is_alive_but_silent(bus: Bus) -> None:
    keys = Keys(bus.namespace)
    watch = WorldWatch(bus.client_session, keys)
    token = bus.server_session.liveliness().declare_token(keys.world_alive)
    server = CommandServer(bus.server_session, bus.namespace)
    server.add(keys.world_cmd("observe"), echo)  # declared, never served
    try:
        assert watch.wait_alive(5.0)
        time.sleep(PROPAGATE_S)
        with pytest.raises(QueryFailed, match=r"the world is alive but did not answer within 0\.5 s"):
            call(bus.client_session, keys.world_cmd("observe"), timeout_s=0.5, watch=watch)
        # a command the live world does not serve is said to be one
        with pytest.raises(QueryFailed, match=r"nobody serves this key, though the world under .* is alive"):
            call(bus.client_session, keys.world_cmd("absent"), timeout_s=20, watch=watch)
    finally:
        server.close()
        token.undeclare()
        watch.close()


def test_no_world_under_the_namespace_names_the_visible_ones(bus: Bus) -> None:
    """A query under a namespace no world serves fails at once, naming the namespaces of the worlds
    the session sees."""
    token = bus.server_session.liveliness().declare_token(f"{bus.namespace}/other/world/alive")
    watch = WorldWatch(bus.client_session, Keys(f"{bus.namespace}/mine"))
    try:
        deadline = time.monotonic() + 5
        while not watch.others() and time.monotonic() < deadline:
            time.sleep(0.05)
        assert watch.others() == [f"{bus.namespace}/other"]
        started = time.monotonic()
        with pytest.raises(QueryFailed, match=rf"no world serves under '{bus.namespace}/mine'; the worlds visible "
                                              rf"serve under '{bus.namespace}/other'"):
            call(bus.client_session, f"{bus.namespace}/mine/world/cmd/reset", timeout_s=20, watch=watch)
        assert time.monotonic() - started < 10
    finally:
        watch.close()
        token.undeclare()


def test_a_followed_process_tells_gone_from_silent(bus: Bus) -> None:
    """With the world's process followed, a token that went while the process runs is a world that
    stopped answering; once the process has ended, the world is gone, with its exit code."""
    keys = Keys(bus.namespace)
    watch = WorldWatch(bus.client_session, keys)
    exit_code: list[int | None] = [None]
    watch.follow_process(lambda: exit_code[0])
    token = bus.server_session.liveliness().declare_token(keys.world_alive)
    try:
        assert watch.wait_alive(5.0)
        token.undeclare()
        deadline = time.monotonic() + 5
        while watch.alive and time.monotonic() < deadline:
            time.sleep(0.01)
        assert watch.gone() is None and watch.hold_s() == float("inf")
        assert "alive but did not answer within 3.0 s" in watch.silent(3.0)
        exit_code[0] = -9
        assert watch.gone() == "the world process is gone (it was killed by SIGKILL (exit code -9))"
    finally:
        watch.close()


def test_refused_says_connection_refused_for_a_closed_port() -> None:
    endpoint = free_tcp_endpoint()
    assert refused(endpoint) == f"connection refused at {endpoint}: nothing listens there"
    with open_session(listen=[endpoint]):
        assert refused(endpoint) is None
    assert refused("udp/127.0.0.1:1") is None  # only TCP is probed
