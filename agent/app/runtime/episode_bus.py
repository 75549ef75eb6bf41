"""An episode's end of the bus, opened first: the agent's session and liveliness token, its link to
the world, and the world, spawned or joined.

Light to import, so that `homebot run` opens it and starts the world before it loads the rest of
the runtime: a spawned world starts, and builds the seed's home, while the agent imports its
libraries and builds its tree. The agent listens before the world starts, and the world connects
to it, so neither side waits for the other to come up or retries a connection (an agent that
listens nowhere connects to the world instead).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import zenoh

from agent.app.agents import announce, open_agent_session
from agent.app.runtime.request import DEFAULT_NAMESPACE, RunRequest, new_run_id
from agent.app.runtime.world_process import WorldProcess, WorldStartError
from worlds.bus.keys import Keys, check_namespace
from worlds.bus.link import WorldLink
from worlds.bus.liveness import describe_worlds, refused
from worlds.bus.session import free_tcp_endpoint, unreached

#: How long a joined endpoint may refuse connections before nothing is taken to listen there (a world
#: started a moment ago opens its port once its imports are done), and how long a joined world's
#: token may take to show once its endpoint accepts connections, before the worlds visible there are
#: taken to be all there is (a namespace that none of them serves). A world announces itself once
#: its first home is built, 1–2 s after it starts on an idle machine.
JOIN_SETTLE_S = 3.0


@dataclass
class EpisodeBus:
    """The run's id, namespace and folder, the agent's session (listening on ``listen``) and token,
    the link to the world at ``endpoint``, the world process once it was spawned here, the request
    it was opened for, and a world process started elsewhere that the request joins, if followed."""

    run_id: str
    namespace: str
    folder: Path
    endpoint: str
    session: zenoh.Session
    listen: list[str]
    token: zenoh.LivelinessToken | None
    link: WorldLink
    world: WorldProcess | None
    request: RunRequest
    followed: WorldProcess | None = None

    @classmethod
    def open(cls, request: RunRequest) -> EpisodeBus:
        """Open the agent's session, announce it, and make the link to the world (not started yet:
        `start_world`).

        Args:
            request: the episode.

        Returns:
            The bus.

        Raises:
            worlds.bus.session.EndpointError: an endpoint cannot be opened.
        """
        run_id = request.run_id or new_run_id(request.seed)
        namespace = check_namespace(request.namespace or (DEFAULT_NAMESPACE if request.connect else f"homebot/{run_id}"))
        folder = request.out_root / run_id
        folder.mkdir(parents=True, exist_ok=True)
        config = request.config
        endpoint = request.connect or free_tcp_endpoint()
        # a spawned world connects to the agent; an agent that listens nowhere connects to the world
        connect = [endpoint] if request.connect or not config.bus.listen else []
        session, listen = open_agent_session(list(config.bus.listen), connect, config.bus.zenoh_config)
        token = None
        try:
            token = announce(session, run_id, namespace, listen)
            link = WorldLink(session, Keys(namespace), config.bus.query_timeout_s)
        except BaseException:
            _close(session, token, None, None)
            raise
        return cls(run_id, namespace, folder, endpoint, session, listen, token, link, None, request)

    def start_world(self) -> None:
        """Spawn the world, unless the request joins one or it is spawned already; it builds its
        seed's home at start when the request asks for neither a scenario nor a scene."""
        request = self.request
        if request.connect is not None or self.world is not None:
            return
        prepared = request.seed if request.scenario is None and request.scene is None else None
        self.world = WorldProcess(self.namespace, self.endpoint, request.config.camera, self.folder / "world.log",
                                  self.listen, prepared, request.config.bus.zenoh_config)
        self.link.follow_process(self.world.process.poll)

    def follow(self, world: WorldProcess) -> None:
        """Follow the world process the request joins, started elsewhere (an evaluation worker's,
        which outlives the episode): it is waited for as a world started here is, and a world that
        ends is reported with how it ended; it is not stopped with the bus.

        Args:
            world: the process.
        """
        self.followed = world
        self.link.follow_process(world.process.poll)

    def wait_ready(self, timeout_s: float) -> None:
        """Wait until the world's liveliness token is there.

        A joined world that cannot be there is reported within seconds: nothing listens at its
        endpoint, or the worlds there serve under other namespaces (named).

        Args:
            timeout_s: how long to wait.

        Raises:
            agent.app.runtime.world_process.WorldStartError: the world exited, was too slow, or
                none answers at the endpoint joined.
        """
        process = self.world or self.followed
        if process is not None:
            process.wait_ready(self.link, timeout_s)
            return
        started = time.monotonic()
        listening_since: float | None = None
        while not self.link.liveness.wait_alive(0.2):
            now = time.monotonic()
            if listening_since is None:
                # a world started a moment ago may not listen yet: a refused connection is final
                # only once it has lasted the settling time; any other reason is final at once
                reason = refused(self.endpoint)
                if reason is None:
                    listening_since = now
                elif now - started >= JOIN_SETTLE_S or not reason.startswith("connection refused"):
                    raise WorldStartError(f"no world answers under {self.namespace!r}: {reason}")
            settled = listening_since is not None and now - listening_since >= JOIN_SETTLE_S
            others = self.link.liveness.others() if settled else []
            if others or now - started >= timeout_s:
                within = "" if others else f" within {timeout_s:g} s"
                why = "" if others else "".join(f"; {reason}" for reason in unreached(self.session, [self.endpoint]))
                raise WorldStartError(f"no world answers under {self.namespace!r} at {self.endpoint}{within}: "
                                      f"{describe_worlds(others)}{why}")

    def world_log(self) -> str:
        """The end of the log of the world process started here or followed, when it has ended; to
        close a message with.

        Returns:
            A newline and the end of its log, or "" when there is no such process or it still runs.
        """
        process = self.world or self.followed
        if process is None or process.process.poll() is None:
            return ""
        return f"\n{process.describe_log()}"

    def close(self) -> None:
        """Stop the world spawned here, withdraw the token and close the session."""
        _close(self.session, self.token, self.link, self.world)


def _close(session: zenoh.Session, token: zenoh.LivelinessToken | None, link: WorldLink | None,
           world: WorldProcess | None) -> None:
    if link is not None:
        link.close()
    if world is not None:
        world.stop()
    if token is not None:
        token.undeclare()
    session.close()
