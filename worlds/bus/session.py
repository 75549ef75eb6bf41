"""Opening Zenoh sessions the one way that works on a loopback-only host, and across hosts with a
Zenoh configuration file.

Multicast scouting cannot find peers on such a host, so it is off; peers meet through explicit
``listen`` and ``connect`` endpoints (``tcp/127.0.0.1:PORT``; ``tls/HOST:PORT`` and
``quic/HOST:PORT`` between hosts). A Zenoh configuration file (JSON5, ``--zenoh-config FILE``) is the
base of a session's settings: TLS certificates with mutual authentication
(``transport/link/tls``), access control (``access_control``), anything Zenoh reads. homebot then
sets ``mode`` (``"peer"``), ``scouting/multicast/enabled`` (false), ``listen/endpoints`` and
``connect/endpoints`` (the command's) where the file leaves them out; a key the file sets wins
(docs/hosts.md).
"""

from __future__ import annotations

import json
import logging
import re
import socket
from pathlib import Path

import zenoh

from worlds.bus.liveness import refused

log = logging.getLogger(__name__)

_ENDPOINT = re.compile(r"^(tcp|udp|tls|quic|unixsock-stream)/.+$")
_HOST_PORT = re.compile(r"^(?P<protocol>tcp|udp|tls|quic)/(?P<host>\[[^\]]+\]|[^:/\[\]]+):(?P<port>\d+)$")

#: The keys homebot sets in a session's configuration unless a Zenoh configuration file does.
#: Zenoh's shared memory is off: each process that sent a message over 3 kB made a 16 MB segment in
#: /dev/shm that outlived a process killed or ended by a worker pool, and an evaluation of 280
#: scenes left 560 of them, 9 GB of memory, until a worker was killed for want of memory.
SHARED_MEMORY = "transport/shared_memory/enabled"
OWN_KEYS = ("mode", "scouting/multicast/enabled", "listen/endpoints", "connect/endpoints", SHARED_MEMORY)


class EndpointError(ValueError):
    """An endpoint that Zenoh cannot use; the text names it."""


class ZenohConfigError(EndpointError):
    """A Zenoh configuration file that cannot be read or used; the text names the file."""


def check_endpoint(endpoint: str) -> str:
    """Check that ``endpoint`` is a Zenoh locator such as ``tcp/127.0.0.1:7447`` or ``tls/host:7447``.

    Args:
        endpoint: the endpoint.

    Returns:
        The endpoint.

    Raises:
        EndpointError: it is not a locator.
    """
    if not _ENDPOINT.match(endpoint):
        raise EndpointError(f"endpoint {endpoint!r}: expected a locator such as 'tcp/127.0.0.1:7447' "
                            "(tcp, udp, tls, quic or unixsock-stream)")
    return endpoint


def free_tcp_endpoint(host: str = "127.0.0.1") -> str:
    """A TCP endpoint on ``host`` with a port the OS just reported free.

    Args:
        host: the host to bind.

    Returns:
        The endpoint, ``tcp/<host>:<port>``.
    """
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind((host, 0))
        return f"tcp/{host}:{probe.getsockname()[1]}"


def load_zenoh_config(path: str | Path) -> zenoh.Config:
    """Read a Zenoh configuration file (JSON5, JSON or YAML, as Zenoh reads them).

    Args:
        path: the file.

    Returns:
        The configuration it holds.

    Raises:
        ZenohConfigError: the file is missing, or Zenoh refuses it (the text says why).
    """
    if not Path(path).is_file():
        raise ZenohConfigError(f"Zenoh config {path}: no such file")
    try:
        return zenoh.Config.from_file(str(path))
    except zenoh.ZError as error:
        raise ZenohConfigError(f"Zenoh config {path}: {_plain(error)}") from None


def session_config(listen: list[str] | None = None, connect: list[str] | None = None,
                   zenoh_config: str | Path | None = None) -> tuple[zenoh.Config, list[str]]:
    """The configuration of a peer session on the given endpoints: the Zenoh configuration file's,
    with homebot's keys (`OWN_KEYS`) set where the file leaves them out: where its value is Zenoh's
    default, and for shared memory (on by default) where the file's text does not name the key.

    Args:
        listen: the endpoints to listen on.
        connect: the endpoints to connect to.
        zenoh_config: a Zenoh configuration file, or None (or "") for none.

    Returns:
        The configuration and the endpoints a session opened with it listens on.

    Raises:
        EndpointError: an endpoint is not a locator.
        ZenohConfigError: the file cannot be used.
    """
    ours = {"mode": "peer", "scouting/multicast/enabled": False,
            "listen/endpoints": [check_endpoint(e) for e in listen or []],
            "connect/endpoints": [check_endpoint(e) for e in connect or []],
            SHARED_MEMORY: False}
    config = load_zenoh_config(zenoh_config) if zenoh_config else zenoh.Config()
    defaults = zenoh.Config()
    text = Path(zenoh_config).read_text(errors="replace") if zenoh_config else ""
    for key in OWN_KEYS:
        if zenoh_config and (config.get_json(key) != defaults.get_json(key)
                             or key == SHARED_MEMORY and _names(text, key)):
            log.info("%s from %s (%s) is used instead of homebot's (%s)", key, zenoh_config,
                     config.get_json(key), json.dumps(ours[key]))
            continue
        try:
            config.insert_json5(key, json.dumps(ours[key]))
        except zenoh.ZError as error:
            raise ZenohConfigError(f"Zenoh config {zenoh_config}: cannot set {key}: {_plain(error)}") from None
    return config, _endpoints(config, "listen/endpoints")


def _names(text: str, key: str) -> bool:
    """Whether a Zenoh configuration file's ``text`` names every part of ``key`` in turn: a file
    may set shared memory on, Zenoh's default, which its value alone does not tell."""
    at = 0
    for part in key.split("/"):
        at = text.find(part, at)
        if at < 0:
            return False
        at += len(part)
    return True


def open_session(listen: list[str] | None = None, connect: list[str] | None = None,
                 zenoh_config: str | Path | None = None) -> zenoh.Session:
    """A peer session with multicast scouting off and the given explicit endpoints, on the settings
    of a Zenoh configuration file if one is given (`session_config`).

    Args:
        listen: the endpoints to listen on.
        connect: the endpoints to connect to.
        zenoh_config: a Zenoh configuration file (TLS, access control), or None (or "") for none.

    Returns:
        The session.

    Raises:
        EndpointError: an endpoint is not a locator, or the session cannot be opened (a port taken,
            a certificate file missing); the text says which.
        ZenohConfigError: the configuration file cannot be used.
    """
    config, listening = session_config(listen, connect, zenoh_config)
    try:
        return zenoh.open(config)
    except zenoh.ZError as error:
        where = f"listen={listening}, connect={_endpoints(config, 'connect/endpoints')}"
        also = f", Zenoh config {zenoh_config}" if zenoh_config else ""
        raise EndpointError(f"cannot open a Zenoh session ({where}{also}): {_plain(error)}") from None


def unreached(session: zenoh.Session, endpoints: list[str], probe_s: float = 1.0) -> list[str]:
    """Why the session has no link to each of ``endpoints`` it has none to, one sentence each.

    Whether a process listens there is probed with a plain TCP connection (tcp and tls endpoints):
    none is "connection refused"; one that took the connection but opened no Zenoh session is a
    TLS handshake that failed (a certificate the listener refused, or one this side does not
    trust) or a peer that turned this session down.

    Args:
        session: an open session.
        endpoints: the endpoints it was to connect to.
        probe_s: how long the TCP probe may take.

    Returns:
        One sentence per endpoint not reached, naming it; empty when every one is reached.
    """
    linked = [str(link.dst) for link in session.info.links()]
    return [_why_unreached(endpoint, probe_s) for endpoint in endpoints
            if not any(_same_place(endpoint, dst) for dst in linked)]


def _why_unreached(endpoint: str, probe_s: float) -> str:
    """The reason no link to ``endpoint`` exists, from a TCP probe where one can be made."""
    match = _HOST_PORT.match(endpoint.split("?")[0].split("#")[0])
    if match is None or match["protocol"] in ("udp", "quic"):
        return f"no Zenoh session was opened with {endpoint} (nothing answers there, or its handshake failed)"
    reason = refused(f"tcp/{match['host']}:{match['port']}", probe_s)
    if reason is not None:
        return reason.replace(f"tcp/{match['host']}:{match['port']}", endpoint)
    if match["protocol"] == "tls":
        return (f"{endpoint} took the connection but opened no Zenoh session: the TLS handshake failed "
                "(the listener refused this side's certificate, or this side does not trust the "
                "listener's: transport/link/tls in the Zenoh config) or the peer turned this session down")
    return (f"{endpoint} took the connection but opened no Zenoh session: not a Zenoh peer, or one that "
            "turned this session down")


def _same_place(endpoint: str, dst: str) -> bool:
    """Whether a link's destination ``dst`` is ``endpoint``: same protocol and port, a host that
    resolves to the same address."""
    want, got = (_HOST_PORT.match(e.split("?")[0].split("#")[0]) for e in (endpoint, dst))
    if want is None or got is None:
        return endpoint == dst
    if (want["protocol"], want["port"]) != (got["protocol"], got["port"]):
        return False
    return bool(_addresses(want["host"]) & _addresses(got["host"]))


def _addresses(host: str) -> set[str]:
    """The addresses ``host`` resolves to (itself when it does not)."""
    host = host.strip("[]")
    try:
        return {info[4][0] for info in socket.getaddrinfo(host, None)} | {host}
    except OSError:
        return {host}


def _plain(error: zenoh.ZError) -> str:
    """Zenoh's error text without the Rust source locations it carries."""
    return re.sub(r"\s+at \S+\.rs:\d+\.?", "", str(error).strip())


def _endpoints(config: zenoh.Config, key: str) -> list[str]:
    """The endpoints a configuration gives a peer under ``key`` (a list, or a table per mode)."""
    value = json.loads(config.get_json(key))
    if isinstance(value, dict):
        value = value.get(json.loads(config.get_json("mode")) or "peer", [])
    return list(value or [])
