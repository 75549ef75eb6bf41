"""Running agents on one machine: how each announces itself, and how a watcher finds them.

Every `homebot run` that listens for watchers declares a Zenoh liveliness token

    homebot/agents/<run id>/<namespace, '/' written as '.'>/<listen endpoint's chunks>

e.g. ``homebot/agents/20250101-120000-seed0-ab12/homebot.20250101-120000-seed0-ab12/tcp/127.0.0.1:7450``.
Its key says all a watcher needs: which run, under which namespace it publishes, and where to
connect to it. An agent whose listen endpoint is taken (another agent holds the default port)
listens on a free port of the same host instead and connects to the taken endpoint, so a watcher
connected to the default endpoint still meets every agent of the machine.
"""

from __future__ import annotations

import errno
import logging
import queue
import re
import socket
import time
from dataclasses import dataclass

import zenoh

from worlds.bus.keys import check_namespace
from worlds.bus.session import EndpointError, ZenohConfigError, open_session, session_config

log = logging.getLogger(__name__)

#: The key prefix of the agents' liveliness tokens.
AGENTS_PREFIX = "homebot/agents"

_CHUNK = re.compile(r"^[^/*$?#]+$")
_TCP = re.compile(r"^tcp/(?P<host>\[[^\]]+\]|[^:/\[\]]+):(?P<port>\d+)$")


@dataclass(frozen=True)
class AgentInfo:
    """A running agent as its liveliness token names it.

    Attributes:
        run_id: the episode's run id.
        namespace: the key prefix its snapshots and events go under.
        endpoint: where a watcher connects to it.
    """

    run_id: str
    namespace: str
    endpoint: str

    @property
    def key(self) -> str:
        """The agent's liveliness token key.

        Returns:
            ``homebot/agents/<run id>/<namespace with '.' for '/'>/<endpoint>``.

        Raises:
            ValueError: the run id or endpoint cannot be written as key chunks (naming which).
        """
        if not _CHUNK.match(self.run_id):
            raise ValueError(f"run id {self.run_id!r}: cannot be a key chunk (no '/', '*', '$', '?', '#')")
        chunks = self.endpoint.split("/")
        if not all(_CHUNK.match(chunk) for chunk in chunks):
            raise ValueError(f"endpoint {self.endpoint!r}: cannot be written as key chunks")
        return "/".join([AGENTS_PREFIX, self.run_id, check_namespace(self.namespace).replace("/", "."), *chunks])

    @classmethod
    def from_key(cls, key: str) -> AgentInfo:
        """Read an agent's liveliness token key.

        Args:
            key: the key.

        Returns:
            The agent it names.

        Raises:
            ValueError: the key is not an agent's token key.
        """
        prefix = AGENTS_PREFIX + "/"
        chunks = key[len(prefix):].split("/") if key.startswith(prefix) else []
        if len(chunks) < 4:
            raise ValueError(f"agent key {key!r}: expected {prefix}<run id>/<namespace>/<endpoint>")
        return cls(chunks[0], check_namespace(chunks[1].replace(".", "/")), "/".join(chunks[2:]))


def open_agent_session(listen: list[str], connect: list[str],
                       zenoh_config: str | None = None) -> tuple[zenoh.Session, list[str]]:
    """An agent's session; a TCP listen endpoint that another process holds is swapped for a free
    port on the same host, and the taken endpoint is connected to instead (one line on stderr says so).

    Args:
        listen: the endpoints the settings say to listen on.
        connect: the endpoints to connect to (the world's).
        zenoh_config: a Zenoh configuration file (`worlds.bus.session.open_session`), or None.

    Returns:
        The session and the endpoints it listens on (a Zenoh configuration file's own, where it
        sets them).

    Raises:
        EndpointError: an endpoint cannot be opened for another reason.
    """
    try:
        return open_session(listen, connect, zenoh_config), session_config(listen, connect, zenoh_config)[1]
    except ZenohConfigError:
        raise
    except EndpointError:
        taken = [endpoint for endpoint in listen if _is_taken(endpoint)]
        if not taken:
            raise
    taken_listen = [_free_like(endpoint) if endpoint in taken else endpoint for endpoint in listen]
    session = open_session(taken_listen, [*connect, *taken], zenoh_config)
    for endpoint, instead in zip(listen, taken_listen):
        if endpoint != instead:
            log.warning("%s is taken by another process: this agent listens on %s and connects to %s",
                        endpoint, instead, endpoint)
    return session, session_config(taken_listen, [*connect, *taken], zenoh_config)[1]


def announce(session: zenoh.Session, run_id: str, namespace: str, listen: list[str]) -> zenoh.LivelinessToken | None:
    """Declare the agent's liveliness token for its first listen endpoint that fits in a key.

    Args:
        session: the agent's session.
        run_id: the run id.
        namespace: the run's namespace.
        listen: the endpoints the session listens on.

    Returns:
        The token (undeclared when the session closes), or None when no endpoint can be announced.
    """
    for endpoint in listen:
        try:
            key = AgentInfo(run_id, namespace, endpoint).key
        except ValueError as error:
            log.debug("not announced: %s", error)
            continue
        return session.liveliness().declare_token(key)
    return None


def find_agents(session: zenoh.Session, wait_s: float, run_id: str | None = None) -> list[AgentInfo]:
    """The agents whose tokens the session sees within ``wait_s``; with ``run_id``, as soon as that one shows.

    Args:
        session: a session connected to an agent's endpoint (the default one reaches them all).
        wait_s: how long to gather tokens.
        run_id: the run to look for, if any.

    Returns:
        The agents still announced at the end, by run id; with ``run_id``, that agent alone (or none).
    """
    inbox: queue.Queue[zenoh.Sample] = queue.Queue()
    subscriber = session.liveliness().declare_subscriber(f"{AGENTS_PREFIX}/**", inbox.put, history=True)
    agents: dict[str, AgentInfo] = {}
    deadline = time.monotonic() + wait_s
    try:
        while (left := deadline - time.monotonic()) > 0:
            try:
                sample = inbox.get(timeout=left)
            except queue.Empty:
                break
            try:
                agent = AgentInfo.from_key(str(sample.key_expr))
            except ValueError as error:
                log.warning("skipped a token: %s", error)
                continue
            if sample.kind == zenoh.SampleKind.DELETE:
                agents.pop(agent.run_id, None)
            elif agent.run_id == run_id:
                return [agent]
            else:
                agents[agent.run_id] = agent
    finally:
        subscriber.undeclare()
    return [] if run_id is not None else [agents[key] for key in sorted(agents)]


def _is_taken(endpoint: str) -> bool:
    """Whether ``endpoint`` is a TCP endpoint whose port another socket already holds."""
    match = _TCP.match(endpoint)
    if match is None:
        return False
    host = match["host"].strip("[]")
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM) as probe:
        try:
            probe.bind((host, int(match["port"])))
        except OSError as error:
            return error.errno == errno.EADDRINUSE
    return False


def _free_like(endpoint: str) -> str:
    """A TCP endpoint on the same host as ``endpoint`` with a port the OS just reported free."""
    match = _TCP.match(endpoint)
    assert match is not None  # only endpoints `_is_taken` matched come here
    host = match["host"].strip("[]")
    with socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind((host, 0))
        return f"tcp/{match['host']}:{probe.getsockname()[1]}"
