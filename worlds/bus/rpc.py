"""Commands over Zenoh queries: one request, one reply, both in the wire codec.

A reply's header always has ``ok``; when it is false, ``error`` says what was wrong with the
request, so a client in any language can report it. The client side never blocks the caller:
`PendingReply.poll` returns at once, which is what a py_trees behaviour needs to stay RUNNING while
the world works, and its ``on_reply`` tells whoever waits meanwhile (the tree between ticks) the
moment there is something to poll. Every query has a deadline.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
import zenoh

from worlds.bus.codec import DEFAULT_LIMITS, Limits, Message, WireError, decode, encode
from worlds.bus.rejections import MAX_REASON_CHARS, RejectionLog

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
    not thread-safe (PyBullet) is only ever touched from one thread: Zenoh's callbacks only queue
    the queries, in the order they came, and the serving thread waits on that queue. Handlers added
    ``concurrent`` (those that only read data that never changes, such as the robot's description)
    are answered from a second thread meanwhile, so they answer while a long command runs.

    Every reply carries ``namespace`` and comes on the queryable's own key, so a client that asked
    with a wildcard can tell who answered. A zero-length request is ``{}``, as a request without a
    payload is. A request whose queue already holds ``max_waiting`` is answered at once with a
    ``busy`` error rather than held. Refusals are logged one line each, rate-limited
    (`worlds.bus.rejections`).

    Args:
        session: the bus session.
        namespace: the namespace served, put in every reply.
        limits: the largest request accepted.
        max_waiting: the most requests held for each thread before it answers them.
    """

    def __init__(self, session: zenoh.Session, namespace: str, limits: Limits = DEFAULT_LIMITS,
                 max_waiting: int = 64) -> None:
        self._session = session
        self._namespace = namespace
        self._limits = limits
        self._max_waiting = max_waiting
        self._queryables: list[Any] = []
        self._waiting: queue.Queue[tuple[zenoh.Query, str, Handler]] = queue.Queue(max_waiting)
        self._concurrent: queue.Queue[tuple[zenoh.Query, str, Handler]] = queue.Queue(max_waiting)
        self.rejections = RejectionLog(log)
        self._stopping = threading.Event()  # the commands' thread is done: the second one stops too

    def add(self, key: str, handler: Handler, concurrent: bool = False) -> None:
        """Answer queries on ``key`` with ``handler``.

        Args:
            key: the key expression; its last chunk names the command in errors (``move_base.yaw``).
            handler: makes the reply from the query's message.
            concurrent: answer from the second thread, beside the commands: only for a handler that
                reads nothing any other handler changes.
        """
        waiting = self._concurrent if concurrent else self._waiting
        self._queryables.append(self._session.declare_queryable(
            key, zenoh.handlers.Callback(lambda query: self._hold(waiting, query, key, handler))))

    def serve(self, stop: threading.Event, check_s: float = 0.05) -> None:
        """Answer queries as they come until ``stop`` is set.

        Args:
            stop: set to stop serving.
            check_s: the longest it waits for a query before looking at ``stop`` again.
        """
        self._stopping.clear()
        beside = threading.Thread(target=self._serve, args=(self._concurrent, stop, check_s),
                                  name="command-server-concurrent", daemon=True)
        beside.start()
        try:
            self._serve(self._waiting, stop, check_s)
        finally:
            self._stopping.set()
            beside.join()

    def close(self) -> None:
        for queryable in self._queryables:
            queryable.undeclare()
        self._queryables.clear()

    def _serve(self, waiting: queue.Queue[tuple[zenoh.Query, str, Handler]], stop: threading.Event,
               check_s: float) -> None:
        while not (stop.is_set() or self._stopping.is_set()):
            try:
                query, key, handler = waiting.get(timeout=check_s)
            except queue.Empty:
                self.rejections.flush()
                continue
            self._answer(query, key, handler)

    def _hold(self, waiting: queue.Queue[tuple[zenoh.Query, str, Handler]], query: zenoh.Query, key: str,
              handler: Handler) -> None:
        """In Zenoh's thread: queue the query, or answer it busy when its queue is full."""
        try:
            waiting.put_nowait((query, key, handler))
        except queue.Full:
            reason = f"busy: the world's queue is full ({self._max_waiting} waiting); try again later"
            self.rejections.rejected(key, reason)
            self._reply(query, key, self._refusal(reason))

    def _answer(self, query: zenoh.Query, key: str, handler: Handler) -> None:
        verb = key.rsplit("/", 1)[-1]
        try:
            raw = query.payload.to_bytes() if query.payload is not None else b""
            meta, arrays = handler(decode(raw, self._limits) if raw else Message())
            reply = encode({"ok": True, **meta, "namespace": self._namespace}, arrays)
        except (WireError, RequestError) as error:
            named = isinstance(error, WireError) and error.field
            reason = f"{verb}.{error.field}: {error.problem}" if named else str(error)
            self.rejections.rejected(key, reason)
            reply = self._refusal(reason)
        except Exception as error:  # a bug must not take the server down; the client is told
            self.rejections.failed(key, error)
            reply = self._refusal(f"internal error: {type(error).__name__}: {str(error)[:MAX_REASON_CHARS]}")
        self._reply(query, key, reply)

    def _refusal(self, reason: str) -> bytes:
        return encode({"ok": False, "error": reason, "namespace": self._namespace})

    @staticmethod
    def _reply(query: zenoh.Query, key: str, payload: bytes) -> None:
        try:
            query.reply(key, payload)
        except zenoh.ZError as error:  # the client went away meanwhile: nobody to tell
            log.debug("no reply on %s: %s", key, error)
        finally:
            query.drop()


class ServerWatch(Protocol):
    """What a client knows of the server behind a key, to say why a query got no reply
    (`worlds.bus.liveness.WorldWatch` is the world's)."""

    def gone(self) -> str | None:
        """Why the server is gone.

        Returns:
            The reason; None while it is there.
        """

    def hold_s(self) -> float:
        """How long a query that Zenoh ended without a reply waits for `gone` to say why.

        Returns:
            Seconds; inf waits to the query's deadline.
        """

    def silent(self, timeout_s: float) -> str:
        """Why no reply came in time.

        Args:
            timeout_s: the query's timeout.

        Returns:
            The reason.
        """

    def unserved(self) -> str:
        """Why nobody serves the key.

        Returns:
            The reason.
        """


class PendingReply:
    """A query in flight. `poll` returns None until the reply arrives, then the reply's message.

    Zenoh hands the reply (and the query's end, with or without one) to a callback in its own
    thread; ``on_reply`` is called there too, so a caller that waits on something else (a tree
    that waits between ticks) wakes as soon as there is something to poll. ``watch``, when given,
    is asked on every poll: once it says the server is gone (its liveliness token went), the query
    fails with that reason at once instead of waiting for its deadline; it also words the reason
    when no reply comes in time or nobody serves the key. A query that Zenoh ends without a reply
    (its server's session closed, or nobody serves the key) waits ``watch.hold_s()`` for the watch
    to say whether the server is gone, since a server that dies ends its queries and drops its
    token at the same moment, in either order.

    Args:
        session: the bus session.
        key: the command's key.
        meta: its metadata.
        arrays: its arrays.
        timeout_s: how long the reply may take.
        watch: what the client knows of the server; plain reasons without it.
        limits: the largest reply accepted.
        on_reply: called (from Zenoh's thread) when the reply arrives or the query ends without one.
    """

    def __init__(
        self,
        session: zenoh.Session,
        key: str,
        meta: dict[str, Any] | None = None,
        arrays: Arrays | None = None,
        timeout_s: float = 10.0,
        watch: ServerWatch | None = None,
        limits: Limits = DEFAULT_LIMITS,
        on_reply: Callable[[], None] | None = None,
    ) -> None:
        self.key = key
        self.timeout_s = timeout_s
        self._watch = watch
        self._limits = limits
        self._on_reply = on_reply
        self._reply: zenoh.Reply | None = None
        self._arrived = threading.Event()  # set once there is a reply, or there will be none
        self._started = time.monotonic()
        self._ended_at: float | None = None  # when the query was seen ended without a reply
        session.get(key, zenoh.handlers.Callback(self._received, self._ended),
                    payload=encode(meta or {}, arrays), timeout=timeout_s)

    @property
    def elapsed_s(self) -> float:
        return time.monotonic() - self._started

    def _received(self, reply: zenoh.Reply) -> None:
        if self._reply is None:  # the first reply counts, as it did through a channel
            self._reply = reply
        self._arrived.set()
        if self._on_reply is not None:
            self._on_reply()

    def _ended(self) -> None:
        self._arrived.set()
        if self._on_reply is not None:
            self._on_reply()

    def poll(self) -> Message | None:
        """The reply if it has come, None while waiting; raises QueryFailed when there will be none.

        Returns:
            The reply, or None.

        Raises:
            QueryFailed: no reply within the timeout, nobody serves the key, or the world is gone.
        """
        ended = self._arrived.is_set()  # read first: a reply is stored before the event is set
        reply = self._reply
        if reply is None:
            reason = self._no_reply(ended)
            if reason is not None:
                raise QueryFailed(f"{self.key}: {reason}")
            return None
        if reply.err is not None:
            if self._timed_out():  # Zenoh reports its own deadline as an error reply
                raise QueryFailed(f"{self.key}: {self._silent()}")
            raise QueryFailed(f"{self.key}: error reply: {reply.err.payload.to_bytes()!r}")
        try:
            message = decode(reply.ok.payload.to_bytes(), self._limits)
        except WireError as error:
            raise QueryFailed(f"{self.key}: malformed reply: {error}") from None
        if message.meta.get("ok") is not True:
            raise QueryFailed(f"{self.key}: {message.meta.get('error', 'the reply says it failed, without a reason')}")
        return message

    def _no_reply(self, ended: bool) -> str | None:
        """Why there is no reply and will be none; None while one may still come."""
        gone = self._watch.gone() if self._watch is not None else None
        if gone:
            return gone
        if self._timed_out():
            return self._silent()
        if not ended:
            return None
        if self._ended_at is None:
            self._ended_at = time.monotonic()
        hold_s = self._watch.hold_s() if self._watch is not None else 0.0
        if time.monotonic() - self._ended_at < hold_s:
            return None
        return self._watch.unserved() if self._watch is not None else "nobody serves this key (is the world running?)"

    def _timed_out(self) -> bool:
        return self.elapsed_s >= self.timeout_s * 0.99  # Zenoh ends a query at its deadline, give or take

    def _silent(self) -> str:
        if self._watch is None:
            return f"no reply within {self.timeout_s:.1f} s"
        return self._watch.silent(self.timeout_s)

    def wait(self, check_s: float = 0.05) -> Message:
        """Block until the reply (for command-line tools and tests, never inside a tree tick).

        Args:
            check_s: the longest it waits without asking whether the server is gone.

        Returns:
            The reply.

        Raises:
            QueryFailed: there will be no reply.
        """
        while (message := self.poll()) is None:
            if self._arrived.is_set():  # ended without a reply: the watch is being waited on
                time.sleep(check_s)
            else:
                self._arrived.wait(check_s)
        return message


def call(
    session: zenoh.Session,
    key: str,
    meta: dict[str, Any] | None = None,
    arrays: Arrays | None = None,
    timeout_s: float = 10.0,
    watch: ServerWatch | None = None,
) -> Message:
    """Send one command and wait for its reply.

    Args:
        session: the bus session.
        key: the command's key.
        meta: its metadata.
        arrays: its arrays.
        timeout_s: how long the reply may take.
        watch: what the client knows of the server (`PendingReply`).

    Returns:
        The reply.

    Raises:
        QueryFailed: there will be no reply.
    """
    return PendingReply(session, key, meta, arrays, timeout_s, watch).wait()
