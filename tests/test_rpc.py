"""Commands over real Zenoh queries on loopback: replies, errors, timeouts, and liveliness."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
import zenoh

from worlds.bus.codec import Message, decode, encode
from worlds.bus.keys import ANY_AGENT_TREE, Keys, check_namespace
from worlds.bus.liveness import LivenessWatch, WorldWatch
from worlds.bus.rpc import CommandServer, PendingReply, QueryFailed, RequestError, call
from worlds.bus.session import EndpointError, check_endpoint, free_tcp_endpoint, open_session

PROPAGATE_S = 0.3  # declarations need a moment to reach the other session


@dataclass
class Bus:
    server_session: zenoh.Session
    client_session: zenoh.Session
    namespace: str


@pytest.fixture
def bus() -> Iterator[Bus]:
    """Two peer sessions: one listening on a free loopback endpoint, one connected to it."""
    endpoint = free_tcp_endpoint()
    server = open_session(listen=[endpoint])
    client = open_session(connect=[endpoint])
    try:
        yield Bus(server, client, f"test/rpc{endpoint.rsplit(':', 1)[1]}")
    finally:
        client.close()
        server.close()


@pytest.fixture
def serve(bus: Bus) -> Iterator[Callable[[dict[str, Callable[[Message], tuple[dict[str, Any], dict]]]], CommandServer]]:
    """Start a CommandServer with the given handlers in a background thread; stop it afterwards."""
    stop = threading.Event()
    threads: list[threading.Thread] = []
    servers: list[CommandServer] = []

    def start(handlers: dict[str, Callable[[Message], tuple[dict[str, Any], dict]]]) -> CommandServer:
        server = CommandServer(bus.server_session, bus.namespace)
        for key, handler in handlers.items():
            server.add(key, handler)
        thread = threading.Thread(target=server.serve, args=(stop,), daemon=True)
        thread.start()
        threads.append(thread)
        servers.append(server)
        time.sleep(PROPAGATE_S)
        return server

    yield start
    stop.set()
    for thread in threads:
        thread.join(timeout=10)
        assert not thread.is_alive(), "the server thread did not stop"
    for server in servers:
        server.close()


def echo(message: Message) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    return {"echo": message.meta}, {name: array * 2 for name, array in message.arrays.items()}


def test_reply_arrives_through_poll(bus: Bus, serve: Any) -> None:
    """`poll` returns None until the reply arrives, then the handler's metadata and arrays."""
    key = f"{bus.namespace}/world/cmd/echo"
    serve({key: echo})
    pending = PendingReply(bus.client_session, key, {"n": 1}, {"v": np.arange(3, dtype=np.int32)}, timeout_s=5)
    deadline = time.monotonic() + 5
    message = None
    while message is None and time.monotonic() < deadline:
        message = pending.poll()
        time.sleep(0.001)
    assert message is not None, "no reply within 5 s"
    assert message.meta == {"ok": True, "echo": {"n": 1}, "namespace": bus.namespace}
    np.testing.assert_array_equal(message.arrays["v"], [0, 2, 4])


def test_reply_through_wait_and_call(bus: Bus, serve: Any) -> None:
    key = f"{bus.namespace}/world/cmd/echo"
    serve({key: echo})
    assert PendingReply(bus.client_session, key, {"a": "x"}, timeout_s=5).wait().meta["echo"] == {"a": "x"}
    reply = call(bus.client_session, key, {"b": 2}, {"m": np.eye(2)}, timeout_s=5)
    assert reply.meta["echo"] == {"b": 2}
    np.testing.assert_array_equal(reply.arrays["m"], 2 * np.eye(2))


def test_several_keys_are_served_by_one_server(bus: Bus, serve: Any) -> None:
    keys = Keys(bus.namespace)
    serve({keys.world_cmd("reset"): lambda m: ({"which": "reset"}, {}),
           keys.world_cmd("observe"): lambda m: ({"which": "observe"}, {})})
    assert call(bus.client_session, keys.world_cmd("observe"), timeout_s=5).meta["which"] == "observe"
    assert call(bus.client_session, keys.world_cmd("reset"), timeout_s=5).meta["which"] == "reset"


def test_request_error_reaches_client_and_server_keeps_serving(bus: Bus, serve: Any) -> None:
    """A RequestError's text comes back as QueryFailed; the next request is answered normally."""
    def handler(message: Message) -> tuple[dict[str, Any], dict]:
        if message.meta.get("bad"):
            raise RequestError("move_base: target (9, 9) is inside a wall")
        return {"fine": True}, {}

    key = f"{bus.namespace}/world/cmd/move_base"
    serve({key: handler})
    with pytest.raises(QueryFailed, match=r"move_base: target \(9, 9\) is inside a wall"):
        call(bus.client_session, key, {"bad": True}, timeout_s=5)
    reply = call(bus.client_session, key, {}, timeout_s=5)
    assert reply.meta == {"ok": True, "fine": True, "namespace": bus.namespace}


def test_unexpected_exception_is_internal_error_and_server_keeps_serving(bus: Bus, serve: Any) -> None:
    calls = []

    def handler(message: Message) -> tuple[dict[str, Any], dict]:
        calls.append(message.meta)
        if len(calls) == 1:
            raise KeyError("missing_thing")
        return {"second": True}, {}

    key = f"{bus.namespace}/world/cmd/buggy"
    serve({key: handler})
    with pytest.raises(QueryFailed, match=r"internal error: KeyError: 'missing_thing'"):
        call(bus.client_session, key, timeout_s=5)
    assert call(bus.client_session, key, timeout_s=5).meta["second"] is True
    assert len(calls) == 2


def test_malformed_request_payload_is_rejected_with_codec_reason(bus: Bus, serve: Any) -> None:
    """Raw bytes that are not the codec never reach the handler; the reply names the codec's reason."""
    handled = []
    key = f"{bus.namespace}/world/cmd/strict"
    serve({key: lambda m: (handled.append(m), ({}, {}))[1]})
    replies = bus.client_session.get(key, payload=b"XXXX\x00\x00\x00\x02{}", timeout=5)
    reply = replies.recv()
    message = decode(reply.ok.payload.to_bytes())
    assert message.meta["ok"] is False
    assert "bad magic" in message.meta["error"]
    replies = bus.client_session.get(key, payload=b"abc", timeout=5)
    assert "truncated" in decode(replies.recv().ok.payload.to_bytes()).meta["error"]
    assert handled == []
    # and the server is still there for well-formed ones
    assert call(bus.client_session, key, timeout_s=5).meta["ok"] is True
    assert len(handled) == 1


def test_unserved_key_fails_fast(bus: Bus) -> None:
    """Nobody serves the key: the query fails with 'nobody serves' long before its deadline."""
    started = time.monotonic()
    with pytest.raises(QueryFailed, match=r"nobody serves this key"):
        call(bus.client_session, f"{bus.namespace}/world/cmd/absent", timeout_s=20)
    assert time.monotonic() - started < 10, "waited for the deadline instead of failing fast"


def test_slow_handler_gives_no_reply_within_timeout(bus: Bus, serve: Any) -> None:
    release = threading.Event()

    def slow(message: Message) -> tuple[dict[str, Any], dict]:
        release.wait(3.0)
        return {}, {}

    key = f"{bus.namespace}/world/cmd/slow"
    serve({key: slow})
    try:
        with pytest.raises(QueryFailed, match=r"no reply within 0\.5 s"):
            call(bus.client_session, key, timeout_s=0.5)
    finally:
        release.set()


def test_error_reply_from_foreign_server_is_reported(bus: Bus) -> None:
    """A queryable that answers with reply_err (not our server) still gives QueryFailed, not a crash."""
    key = f"{bus.namespace}/world/cmd/foreign"

    def answer(query: zenoh.Query) -> None:
        query.reply_err(b"nope")

    queryable = bus.server_session.declare_queryable(key, answer)
    try:
        time.sleep(PROPAGATE_S)
        with pytest.raises(QueryFailed, match=r"error reply: b'nope'"):
            call(bus.client_session, key, timeout_s=5)
    finally:
        queryable.undeclare()


def test_reply_without_ok_is_a_failure(bus: Bus) -> None:
    key = f"{bus.namespace}/world/cmd/foreign"
    queryable = bus.server_session.declare_queryable(key, lambda q: q.reply(q.key_expr, encode({"x": 1})))
    try:
        time.sleep(PROPAGATE_S)
        with pytest.raises(QueryFailed, match=r"the reply says it failed, without a reason"):
            call(bus.client_session, key, timeout_s=5)
    finally:
        queryable.undeclare()


def test_liveness_watch_follows_token_and_gone_fails_pending_query(bus: Bus) -> None:
    """The token is seen; once it is undeclared `gone` gives a reason and a waiting query fails with it."""
    keys = Keys(bus.namespace)
    watch = WorldWatch(bus.client_session, keys)
    try:
        assert watch.gone() is None
        token = bus.server_session.liveliness().declare_token(keys.world_alive)
        assert watch.wait_alive(5.0), "the liveliness token was not seen"
        assert watch.gone() is None
        # a queryable that is declared but never served: the query would wait for its deadline
        server = CommandServer(bus.server_session, bus.namespace)
        server.add(keys.world_cmd("observe"), echo)
        time.sleep(PROPAGATE_S)
        pending = PendingReply(bus.client_session, keys.world_cmd("observe"), timeout_s=60, watch=watch)
        assert pending.poll() is None
        token.undeclare()
        deadline = time.monotonic() + 5
        while watch.gone() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        reason = watch.gone()
        assert reason is not None and keys.world_alive in reason
        assert not watch.alive
        started = time.monotonic()
        with pytest.raises(QueryFailed, match=r"the world is gone from the bus \(its liveliness token .* was dropped"):
            pending.wait()
        assert time.monotonic() - started < 5
        server.close()
    finally:
        watch.close()


def test_liveness_watch_sees_token_declared_before_it() -> None:
    """`history=True`: a token that existed before the watch started is seen too."""
    endpoint = free_tcp_endpoint()
    with open_session(listen=[endpoint]) as world, open_session(connect=[endpoint]) as agent:
        token = world.liveliness().declare_token("test/early/world/alive")
        time.sleep(PROPAGATE_S)
        watch = LivenessWatch(agent, "test/early/world/alive")
        try:
            assert watch.wait_alive(5.0)
            token.undeclare()
        finally:
            watch.close()


def test_wait_alive_times_out_without_token(bus: Bus) -> None:
    watch = LivenessWatch(bus.client_session, f"{bus.namespace}/world/alive")
    try:
        assert watch.wait_alive(0.2) is False
        assert watch.gone() is None  # never seen is not gone
    finally:
        watch.close()


def test_keys_layout() -> None:
    keys = Keys("homebot/run-1")
    assert keys.world_cmd("reset") == "homebot/run-1/world/cmd/reset"
    assert keys.world_description == "homebot/run-1/world/robot/description"
    assert keys.world_alive == "homebot/run-1/world/alive"
    assert keys.agent_tree == "homebot/run-1/agent/tree"
    assert keys.agent_events == "homebot/run-1/agent/events"
    assert ANY_AGENT_TREE == "**/agent/tree"


@pytest.mark.parametrize("namespace", ["", "a/*", "a/**", "**", "a//b", "/a", "a/", "a b", "a$b", "a?b", "a#b"])
def test_keys_rejects_wildcards_and_empty_chunks(namespace: str) -> None:
    with pytest.raises(ValueError, match="namespace"):
        Keys(namespace)
    with pytest.raises(ValueError, match="namespace"):
        check_namespace(namespace)


@pytest.mark.parametrize("namespace", ["homebot", "homebot/abc-123", "a_b/C-9/x"])
def test_keys_accepts_plain_namespaces(namespace: str) -> None:
    assert Keys(namespace).namespace == namespace


@pytest.mark.parametrize("endpoint", ["localhost:7447", "127.0.0.1:7447", "", "tcp/", "http://x:1"])
def test_check_endpoint_rejects_non_locators(endpoint: str) -> None:
    with pytest.raises(EndpointError, match="expected a locator"):
        check_endpoint(endpoint)
    with pytest.raises(EndpointError):
        open_session(listen=[endpoint])


def test_check_endpoint_accepts_locators() -> None:
    for endpoint in ("tcp/127.0.0.1:7447", "udp/127.0.0.1:7447", "unixsock-stream//tmp/x.sock"):
        assert check_endpoint(endpoint) == endpoint


def test_free_tcp_endpoint_is_a_usable_loopback_locator() -> None:
    endpoint = free_tcp_endpoint()
    assert endpoint.startswith("tcp/127.0.0.1:")
    assert 0 < int(endpoint.rsplit(":", 1)[1]) < 65536
    check_endpoint(endpoint)


def test_listening_twice_on_one_endpoint_is_an_endpoint_error() -> None:
    endpoint = free_tcp_endpoint()
    with open_session(listen=[endpoint]):
        with pytest.raises(EndpointError, match=r"cannot open a Zenoh session"):
            open_session(listen=[endpoint])


def test_on_reply_is_called_once_the_reply_is_in_and_when_none_will_come(bus: Bus, serve: Any) -> None:
    """The hook that wakes a waiting tree: called when the reply arrives, and when the query ends
    without one (nobody serves the key), each time with something for `poll` to give."""
    key = f"{bus.namespace}/world/cmd/echo"
    serve({key: echo})
    arrived = threading.Event()
    pending = PendingReply(bus.client_session, key, {"n": 2}, timeout_s=5, on_reply=arrived.set)
    assert arrived.wait(5.0)
    assert pending.poll().meta["echo"] == {"n": 2}
    ended = threading.Event()
    unserved = PendingReply(bus.client_session, f"{bus.namespace}/world/cmd/absent", timeout_s=20, on_reply=ended.set)
    assert ended.wait(10.0)
    with pytest.raises(QueryFailed, match=r"nobody serves this key"):
        unserved.poll()
