"""Opening Zenoh sessions the one way that works on a loopback-only host.

Multicast scouting cannot find peers on such a host, so it is always off; peers meet through
explicit ``listen`` and ``connect`` endpoints (``tcp/127.0.0.1:PORT``).
"""

from __future__ import annotations

import json
import re
import socket

import zenoh

_ENDPOINT = re.compile(r"^(tcp|udp|unixsock-stream)/.+$")


class EndpointError(ValueError):
    """An endpoint that Zenoh cannot use; the text names it."""


def check_endpoint(endpoint: str) -> str:
    """Check that ``endpoint`` is a Zenoh locator such as ``tcp/127.0.0.1:7447``.

    Args:
        endpoint: the endpoint.

    Returns:
        The endpoint.

    Raises:
        EndpointError: it is not a locator.
    """
    if not _ENDPOINT.match(endpoint):
        raise EndpointError(f"endpoint {endpoint!r}: expected a locator such as 'tcp/127.0.0.1:7447'")
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


def open_session(listen: list[str] | None = None, connect: list[str] | None = None) -> zenoh.Session:
    """A peer session with multicast scouting off and the given explicit endpoints.

    Args:
        listen: the endpoints to listen on.
        connect: the endpoints to connect to.

    Returns:
        The session.

    Raises:
        EndpointError: an endpoint is not a locator.
    """
    listen = [check_endpoint(e) for e in listen or []]
    connect = [check_endpoint(e) for e in connect or []]
    config = zenoh.Config()
    config.insert_json5("mode", '"peer"')
    config.insert_json5("scouting/multicast/enabled", "false")
    config.insert_json5("listen/endpoints", json.dumps(listen))
    config.insert_json5("connect/endpoints", json.dumps(connect))
    try:
        return zenoh.open(config)
    except zenoh.ZError as error:
        raise EndpointError(f"cannot open a Zenoh session (listen={listen}, connect={connect}): {error}") from None
