"""Knowing whether the world is there, and saying why a query to it got no reply.

A world announces itself with a liveliness token (``<ns>/world/alive``). `LivenessWatch` follows one
token. `WorldWatch` follows the token of the world an agent talks to, the world's process when the
agent started it, and the other worlds its session can see, and turns what it knows into the
reason a query failed: the world is gone (its token dropped; with the process's exit code when
the agent holds it), the world is alive but did not answer in time (frozen, or too busy), or
no world serves under the namespace (with the namespaces of the worlds that are visible).
"""

from __future__ import annotations

import math
import re
import signal
import socket
import threading
import time
from collections.abc import Callable

import zenoh

from worlds.bus.keys import Keys

#: Every world's liveliness token, whatever its namespace.
WORLD_TOKENS = "**/world/alive"

#: How long a query that ended without a reply while the world's token was there waits for the
#: token to go: a world that was killed ends the query and drops its token at the same moment, in
#: either order, and the reason must be that it is gone, not that nobody serves the key.
SETTLE_S = 1.0

_TCP = re.compile(r"^tcp/(?P<host>\[[^\]]+\]|[^:/\[\]]+):(?P<port>\d+)$")


class LivenessWatch:
    """Follows one liveliness token; `gone` gives a reason once the token has been seen and lost.

    Args:
        session: the bus session.
        key: the token's key.
    """

    def __init__(self, session: zenoh.Session, key: str) -> None:
        self.key = key
        self._lock = threading.Lock()
        self._alive = threading.Event()  # set while the token is there
        self._lost_at: float | None = None
        self._subscriber = session.liveliness().declare_subscriber(key, self._on_sample, history=True)

    def _on_sample(self, sample: zenoh.Sample) -> None:
        with self._lock:
            if sample.kind == zenoh.SampleKind.PUT:
                self._lost_at = None
                self._alive.set()
            else:
                self._lost_at = time.monotonic()
                self._alive.clear()

    @property
    def alive(self) -> bool:
        return self._alive.is_set()

    @property
    def lost(self) -> bool:
        """Whether the token was there and has gone."""
        with self._lock:
            return self._lost_at is not None

    def gone(self) -> str | None:
        """Why the world is gone, once its liveliness token has been dropped; None while it is there.

        Returns:
            The reason, or None.
        """
        if not self.lost:
            return None
        # From the token alone an ended process and one frozen or cut off for longer than the
        # session's lease look the same: both drop the token.
        return (f"the world is gone from the bus (its liveliness token {self.key} was dropped: its process ended, "
                "or was frozen or cut off for longer than the Zenoh lease, 10 s by default)")

    def wait_alive(self, timeout_s: float) -> bool:
        """Wait until the token is present, at most ``timeout_s``; return as soon as it comes.

        Args:
            timeout_s: how long to wait.

        Returns:
            Whether the token is present.
        """
        return self._alive.wait(timeout_s)

    def close(self) -> None:
        self._subscriber.undeclare()


class WorldWatch(LivenessWatch):
    """What an agent knows of the world it talks to, to say why a query got no reply (the
    `worlds.bus.rpc.ServerWatch` a `WorldLink` hands its queries): a `LivenessWatch` of the world's
    token that follows its process too, once told to, and sees which other worlds there are.

    Args:
        session: the agent's session.
        keys: the world's namespace.
    """

    def __init__(self, session: zenoh.Session, keys: Keys) -> None:
        super().__init__(session, keys.world_alive)
        self.session = session
        self.keys = keys
        self._exit_code: Callable[[], int | None] | None = None

    def follow_process(self, exit_code: Callable[[], int | None]) -> None:
        """Follow the world's process too (one this agent started): a token that went while the
        process runs is a world that stopped answering, not one that is gone.

        Args:
            exit_code: the process's exit code, None while it runs (`subprocess.Popen.poll`).
        """
        self._exit_code = exit_code

    def gone(self) -> str | None:
        """Why the world is gone: its process, when followed, ended; else its token was dropped.

        Returns:
            The reason, or None while the world is there, or its process still runs.
        """
        if self._exit_code is None:
            return super().gone()
        code = self._exit_code()
        return None if code is None else f"the world process is gone ({describe_exit(code)})"

    def hold_s(self) -> float:
        """How long a query that ended without a reply, and without `gone` saying why, waits for it.

        Returns:
            `SETTLE_S` while the token is there; until the query's deadline (inf) when the token went
            but the process still runs; 0 when the token was never seen.
        """
        if self.alive:
            return SETTLE_S
        return math.inf if self.lost else 0.0

    def silent(self, timeout_s: float) -> str:
        """Why no reply came within ``timeout_s``.

        Args:
            timeout_s: the query's timeout.

        Returns:
            The reason.
        """
        if self.alive:
            return f"the world is alive but did not answer within {timeout_s:.1f} s"
        if self.lost:
            return (f"the world is alive but did not answer within {timeout_s:.1f} s (its process runs, but its "
                    "Zenoh session went silent: is it stopped or frozen?)")
        return f"no reply within {timeout_s:.1f} s: {self.absent()}"

    def unserved(self) -> str:
        """Why nobody serves a key of the world.

        Returns:
            The reason.
        """
        if self.alive:
            return f"nobody serves this key, though the world under {self.keys.namespace!r} is alive"
        return self.absent()

    def absent(self) -> str:
        """Why no world answers under the namespace: the namespaces of the worlds that are visible.

        Returns:
            The reason.
        """
        return f"no world serves under {self.keys.namespace!r}; {describe_worlds(self.others())}"

    def others(self) -> list[str]:
        """The namespaces of the other worlds the session sees.

        Returns:
            The namespaces, sorted.
        """
        return [name for name in visible_worlds(self.session) if name != self.keys.namespace]


def visible_worlds(session: zenoh.Session, timeout_s: float = 1.0) -> list[str]:
    """The namespaces of the worlds whose tokens ``session`` sees.

    Args:
        session: a session.
        timeout_s: how long the answers may take (the session knows its peers' tokens: they are
            usually in at once).

    Returns:
        The namespaces, sorted.
    """
    suffix = "/world/alive"
    keys = {str(reply.ok.key_expr) for reply in session.liveliness().get(WORLD_TOKENS, timeout=timeout_s)
            if reply.ok is not None}
    return sorted(key[: -len(suffix)] for key in keys if key.endswith(suffix))


def describe_worlds(namespaces: list[str]) -> str:
    """The visible worlds in words.

    Args:
        namespaces: their namespaces.

    Returns:
        e.g. ``the worlds visible serve under 'homebot/a', 'homebot/b'``.
    """
    if not namespaces:
        return "no world is visible from here"
    return "the worlds visible serve under " + ", ".join(repr(name) for name in namespaces)


def refused(endpoint: str, timeout_s: float = 2.0) -> str | None:
    """Why nothing accepts connections at a TCP ``endpoint``; None when something does (or it is not TCP).

    Args:
        endpoint: a locator such as ``tcp/127.0.0.1:7447``.
        timeout_s: how long the connection may take.

    Returns:
        The reason, or None.
    """
    match = _TCP.match(endpoint)
    if match is None:
        return None
    try:
        with socket.create_connection((match["host"].strip("[]"), int(match["port"])), timeout=timeout_s):
            return None
    except ConnectionRefusedError:
        return f"connection refused at {endpoint}: nothing listens there"
    except TimeoutError:
        return f"no answer from {endpoint} within {timeout_s:g} s (is the host up, and the port open?)"
    except OSError as error:
        return f"cannot reach {endpoint}: {error.strerror or error}"


def describe_exit(code: int) -> str:
    """A process's exit code in words.

    Args:
        code: the code, negative for a signal (`subprocess.Popen.returncode`).

    Returns:
        e.g. ``it was killed by SIGKILL (exit code -9)`` or ``it exited with code 1``.
    """
    if code < 0:
        try:
            return f"it was killed by {signal.Signals(-code).name} (exit code {code})"
        except ValueError:
            return f"it was killed by signal {-code} (exit code {code})"
    return f"it exited with code {code}"
