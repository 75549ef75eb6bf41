"""Commands over Zenoh queries: one request, one reply, both in the wire codec.

A reply's header always has ``ok``; when it is false, ``error`` says what was wrong with the
request, so a client in any language can report it. The client side never blocks the caller:
`PendingReply.poll` returns at once, which is what a py_trees behaviour needs to stay RUNNING while
the world works. Every query has a deadline.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import numpy as np
import zenoh

from worlds.bus.codec import DEFAULT_LIMITS, Limits, Message, WireError, decode, encode

log = logging.getLogger(__name__)

Arrays = dict[str, np.ndarray]
Handler = Callable[[Message], tuple[dict[str, Any], Arrays]]


class RequestError(ValueError):
    """A request the server understood but cannot carry out; its text goes back to the client."""


class QueryFailed(RuntimeError):
    """A query that got no usable reply: an error reply, a timeout, or nobody serving the key."""


class CommandServer:
    """Serves handlers on queryables, one request at a time, from the thread that calls `serve`.

    Handlers run in the serving thread rather than Zenoh's callback threads, so a simulator that is
    not thread-safe (PyBullet) is only ever touched from one thread.

    Args:
        session: the bus session.
        limits: the largest request accepted.
    """

    def __init__(self, session: zenoh.Session, limits: Limits = DEFAULT_LIMITS) -> None:
        self._session = session
        self._limits = limits
        self._queryables: list[tuple[Any, Handler]] = []

    def add(self, key: str, handler: Handler) -> None:
        """Answer queries on ``key`` with ``handler``.

        Args:
            key: the key expression.
            handler: makes the reply from the query's message.
        """
        self._queryables.append((self._session.declare_queryable(key), handler))

    def serve(self, stop: threading.Event, idle_sleep_s: float = 0.001) -> None:
        """Answer queries until ``stop`` is set.

        Args:
            stop: set to stop serving.
            idle_sleep_s: how long to sleep when no query waits.
        """
        while not stop.is_set():
            if not self.serve_pending():
                time.sleep(idle_sleep_s)

    def serve_pending(self) -> bool:
        """Answer every query waiting now; return whether there was any.

        Returns:
            Whether any query was answered.
        """
        served = False
        for queryable, handler in self._queryables:
            query = queryable.try_recv()
            if query is not None:
                self._answer(query, handler)
                served = True
        return served

    def close(self) -> None:
        for queryable, _ in self._queryables:
            queryable.undeclare()
        self._queryables.clear()

    def _answer(self, query: zenoh.Query, handler: Handler) -> None:
        key = str(query.key_expr)
        try:
            raw = query.payload.to_bytes() if query.payload is not None else encode({})
            meta, arrays = handler(decode(raw, self._limits))
            reply = encode({"ok": True, **meta}, arrays)
        except (WireError, RequestError) as error:
            log.info("rejected %s: %s", key, error)
            reply = encode({"ok": False, "error": str(error)})
        except Exception as error:  # a bug must not take the server down; the client is told
            log.exception("handler for %s raised", key)
            reply = encode({"ok": False, "error": f"internal error: {type(error).__name__}: {error}"})
        query.reply(query.key_expr, reply)
        query.drop()


class PendingReply:
    """A query in flight. `poll` returns None until the reply arrives, then the reply's message.

    ``gone`` is asked on every poll; when it returns a reason (the server's liveliness token went),
    the query fails with that reason at once instead of waiting for its deadline.

    Args:
        session: the bus session.
        key: the command's key.
        meta: its metadata.
        arrays: its arrays.
        timeout_s: how long the reply may take.
        gone: says why the server is gone, if it is.
        limits: the largest reply accepted.
    """

    def __init__(
        self,
        session: zenoh.Session,
        key: str,
        meta: dict[str, Any] | None = None,
        arrays: Arrays | None = None,
        timeout_s: float = 10.0,
        gone: Callable[[], str | None] | None = None,
        limits: Limits = DEFAULT_LIMITS,
    ) -> None:
        self.key = key
        self.timeout_s = timeout_s
        self._gone = gone
        self._limits = limits
        self._started = time.monotonic()
        self._replies = session.get(key, payload=encode(meta or {}, arrays), timeout=timeout_s)

    @property
    def elapsed_s(self) -> float:
        return time.monotonic() - self._started

    def poll(self) -> Message | None:
        """The reply if it has come, None while waiting; raises QueryFailed when there will be none.

        Returns:
            The reply, or None.

        Raises:
            QueryFailed: no reply within the timeout, nobody serves the key, or the world is gone.
        """
        try:
            reply = self._replies.try_recv()
        except zenoh.ZError:
            if self.elapsed_s >= self.timeout_s * 0.99:
                raise QueryFailed(f"{self.key}: no reply within {self.timeout_s:.1f} s") from None
            raise QueryFailed(f"{self.key}: nobody serves this key (is the world running?)") from None
        if reply is None:
            reason = self._gone() if self._gone else None
            if reason:
                raise QueryFailed(f"{self.key}: {reason}")
            if self.elapsed_s > self.timeout_s:
                raise QueryFailed(f"{self.key}: no reply within {self.timeout_s:.1f} s")
            return None
        if reply.err is not None:
            if self.elapsed_s >= self.timeout_s * 0.99:  # Zenoh reports its own deadline as an error reply
                raise QueryFailed(f"{self.key}: no reply within {self.timeout_s:.1f} s")
            raise QueryFailed(f"{self.key}: error reply: {reply.err.payload.to_bytes()!r}")
        try:
            message = decode(reply.ok.payload.to_bytes(), self._limits)
        except WireError as error:
            raise QueryFailed(f"{self.key}: malformed reply: {error}") from None
        if message.meta.get("ok") is not True:
            raise QueryFailed(f"{self.key}: {message.meta.get('error', 'the reply says it failed, without a reason')}")
        return message

    def wait(self, poll_interval_s: float = 0.001) -> Message:
        """Block until the reply (for command-line tools and tests, never inside a tree tick).

        Args:
            poll_interval_s: how long to sleep between polls.

        Returns:
            The reply.

        Raises:
            QueryFailed: there will be no reply.
        """
        while (message := self.poll()) is None:
            time.sleep(poll_interval_s)
        return message


def call(
    session: zenoh.Session,
    key: str,
    meta: dict[str, Any] | None = None,
    arrays: Arrays | None = None,
    timeout_s: float = 10.0,
    gone: Callable[[], str | None] | None = None,
) -> Message:
    """Send one command and wait for its reply.

    Args:
        session: the bus session.
        key: the command's key.
        meta: its metadata.
        arrays: its arrays.
        timeout_s: how long the reply may take.
        gone: says why the server is gone, if it is.

    Returns:
        The reply.

    Raises:
        QueryFailed: there will be no reply.
    """
    return PendingReply(session, key, meta, arrays, timeout_s, gone).wait()
