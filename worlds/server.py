"""The world server: one simulated home answering commands over Zenoh.

Queryables (all under ``<ns>``, see `worlds.bus.keys`):

- ``world/cmd/reset``      {"seed": int >= 0, "n_rooms": optional 4..10} -> scenario, home size and bounds, pose
                           ({"seed", "tabletop": task} -> a tabletop exploration scene instead)
- ``world/cmd/observe``    {"camera": "head" | "wrist"} -> pose, camera, labels + arrays rgb (H,W,3
                           uint8), depth (H,W float32 metres, 0 = no return), seg (H,W int32 ids, -1 = nothing)
- ``world/cmd/move_base``  {"path": [[x, y], ...], "yaw": optional} -> pose, reached, contact, the route driven
- ``world/cmd/arm_state``  {} -> joint positions, TCP pose, gripper width, what it holds
- ``world/cmd/arm_trajectory`` {"dt", "stop_on_contact", "stop_on_new_contact"} + array samples (N, 8)
  -> reached, errors, contacts
- ``world/cmd/gripper``    {"action": "open" | "close"} -> what it holds
- ``world/cmd/episode_report`` {} -> the evaluator's record of the episode since the last home reset
                           (`worlds.evaluation`): for the runtime once the tree is done, never for behaviours
- ``world/robot/description`` {} -> robot size, cameras, URDF, arm joints and limits

and the liveliness token ``world/alive`` while serving. PyBullet lives in the serving thread: the
`World` is created, used and closed there, and `CommandServer` runs every command in that thread,
one at a time. ``description`` only reads what was fixed before serving began, so it is answered
from a second thread, also while a long command (a reset, a trajectory) runs. Every reply carries
the namespace; every request with an array its command does not take is refused.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import signal
import sys
import threading
from typing import Any

import zenoh

from worlds.bus.codec import Message
from worlds.bus.keys import Keys
from worlds.bus.rpc import Arrays, CommandServer, Handler, RequestError
from worlds.bus.session import EndpointError, load_zenoh_config, open_session
from worlds import commands
from worlds.evaluation import EpisodeRecord
from worlds.home import generate_home
from worlds.manipulation import ArmState
from worlds.robot import CameraConfig
from worlds.robot_arm import arm_spec, robot_description
from worlds.route import driven_route
from worlds.scenario import make_scenario
from worlds.sim import World
from worlds.tabletop import tabletop_variant
from worlds.tabletop_scene import TABLE_HEIGHT

log = logging.getLogger(__name__)

#: The longest path one move_base may ask for; longer requests are refused, not truncated.
MAX_PATH_M = 200.0
DEFAULT_LISTEN = "tcp/127.0.0.1:7447"


class WorldServer:
    """Serves one `World` under a namespace. ``ready`` is set once every queryable is declared.

    Args:
        session: the open Zenoh session to serve on.
        namespace: the key prefix of this run (`worlds.bus.keys.Keys`).
        camera: the head camera; `CameraConfig`'s defaults when None.
    """

    def __init__(self, session: zenoh.Session, namespace: str, camera: CameraConfig | None = None) -> None:
        self.session = session
        self.keys = Keys(namespace)
        self.camera = camera or CameraConfig()
        self.ready = threading.Event()
        self._world: World | None = None
        self._record: EpisodeRecord | None = None  # the evaluator's, for the home episode under way
        # the reset done at start and its reply, until another command comes
        self._prepared: tuple[dict[str, Any], tuple[dict[str, Any], Arrays]] | None = None
        self._described: dict[str, Any] = {}  # the robot's description, fixed before serving begins

    def serve(self, stop: threading.Event, seed: int | None = None) -> None:
        """Build the world (reset to ``seed`` if given) and answer commands until ``stop`` is set.

        A world reset to ``seed`` at start answers a first command that asks for just that reset,
        ``{"seed": seed}``, with the home it has built, without building it again: an agent that
        starts its world with the seed it will ask for has the home built while it gets ready.

        Args:
            stop: set to stop serving.
            seed: the home to reset to before the first command, if any.
        """
        self._world = World(self.camera)
        self._described = robot_description(self.camera)
        server = CommandServer(self.session, self.keys.namespace)
        token = None
        try:
            if seed is not None:
                self._prepared = ({"seed": seed}, self._reset(Message({"seed": seed})))
            server.add(self.keys.world_cmd("reset"), self._checked("reset", self._reset))
            for verb, handler in (("observe", self._observe), ("move_base", self._move_base),
                                  ("arm_state", self._arm_state), ("arm_trajectory", self._arm_trajectory),
                                  ("gripper", self._gripper), ("episode_report", self._episode_report)):
                server.add(self.keys.world_cmd(verb), self._checked(verb, self._after_prepared(handler)))
            server.add(self.keys.world_description, self._checked("description", self._description), concurrent=True)
            token = self.session.liveliness().declare_token(self.keys.world_alive)
            self.ready.set()
            log.info("world serving under %s", self.keys.namespace)
            server.serve(stop)
        finally:
            if token is not None:
                token.undeclare()
            server.close()
            self._world.close()
            self._world = None
            log.info("world under %s stopped", self.keys.namespace)

    @property
    def world(self) -> World | None:
        """The world being served, for a caller in the serving thread between commands.

        Returns:
            The `World`; None before `serve` builds it and after it stops.
        """
        return self._world

    def _built(self, verb: str) -> World:
        assert self._world is not None  # handlers only run inside serve()
        if not self._world.ready:
            raise RequestError(f"{verb}: no home yet; send reset first")
        return self._world

    @staticmethod
    def _checked(verb: str, handler: Handler) -> Handler:
        """``handler``, after the request's arrays are checked against what ``verb`` takes."""
        def handle(request: Message) -> tuple[dict[str, Any], Arrays]:
            commands.check_arrays(verb, request.arrays)
            return handler(request)
        return handle

    def _after_prepared(self, handler: Handler) -> Handler:
        """``handler``, after which the home built at start no longer answers a reset."""
        def handle(request: Message) -> tuple[dict[str, Any], Arrays]:
            self._prepared = None
            return handler(request)
        return handle

    def _reset(self, request: Message) -> tuple[dict[str, Any], Arrays]:
        prepared, self._prepared = self._prepared, None
        if prepared is not None and prepared[0] == request.meta:
            return prepared[1]
        wanted = commands.parse_reset(request.meta)
        assert self._world is not None
        if wanted.tabletop is not None:
            scene = tabletop_variant(wanted.tabletop, wanted.seed)
            base_pose = self._world.start_tabletop(scene)
            self._record = None
            table = {"size": list(scene.table_size), "height": TABLE_HEIGHT, "colour": scene.table_colour}
            tabletop = {"task": scene.task, "seed": scene.seed, "table": table}
            return {"tabletop": tabletop, "base_pose": list(base_pose)}, {}
        home = wanted.home or generate_home(wanted.seed, wanted.n_rooms)
        if wanted.scenario is not None:
            commands.check_start_pose(home, wanted.scenario.start_pose)
        scenario = wanted.scenario or make_scenario(home, wanted.seed)
        try:
            record = EpisodeRecord(home, scenario, self.camera, scenario.start_pose[:2])
        except ValueError as error:  # a scenario about nothing in this home
            raise RequestError(f"reset.{error}") from None
        self._world.start(home, scenario)
        self._record = record
        return {
            "scenario": scenario.to_dict(),
            "home": {
                "area_m2": home.area_m2,
                "bounds": list(home.bounds),
            },
            "base_pose": list(self._world.base_pose),
        }, {}

    def _observe(self, request: Message) -> tuple[dict[str, Any], Arrays]:
        camera = commands.parse_observe(request.meta)
        world = self._built("observe")
        frame = world.observe(camera)
        if camera == "head" and self._record is not None:
            self._record.saw(frame, world.base_pose)
        meta = {
            "base_pose": list(world.base_pose),
            "sensor": camera,
            "camera": (self.camera if camera == "head" else world.wrist_camera).to_dict(),
            "camera_pose": frame.camera_pose.tolist(),
            "labels": frame.labels,
            "render_ms": frame.render_ms,
            "observation": world.observations,
        }
        return meta, {"rgb": frame.rgb, "depth": frame.depth, "seg": frame.seg}

    def _move_base(self, request: Message) -> tuple[dict[str, Any], Arrays]:
        path, yaw = commands.parse_move_base(request.meta)
        world = self._built("move_base")
        x, y, _ = world.base_pose
        length = sum(math.dist(a, b) for a, b in zip([(x, y), *path], path))
        if length > MAX_PATH_M:
            raise RequestError(f"move_base.path: {length:.1f} m long, more than the {MAX_PATH_M:g} m allowed")
        try:
            result = world.move_base(path, yaw)
        except ValueError as error:  # holding a handle: the base cannot leave
            raise RequestError(str(error)) from None
        route = driven_route((x, y), path, result.travelled_m, result.base_pose[:2])
        if self._record is not None:
            self._record.drove(route, result.travelled_m)
        return {
            "base_pose": list(result.base_pose),
            "reached": result.reached,
            "contact": result.contact,
            "contact_point": list(result.contact_point) if result.contact_point else None,
            "travelled_m": result.travelled_m,
            "driven": [[round(px, 4), round(py, 4)] for px, py in route],
        }, {}

    def _episode_report(self, request: Message) -> tuple[dict[str, Any], Arrays]:
        commands.parse_episode_report(request.meta)
        self._built("episode_report")
        if self._record is None:
            raise RequestError("episode_report: the world holds a tabletop scene; only a home episode is recorded")
        return self._record.report(), {}

    def _description(self, request: Message) -> tuple[dict[str, Any], Arrays]:
        """From the second thread: reads only what `serve` fixed before it began."""
        commands.parse_description(request.meta)
        return self._described, {}

    def _arm_state(self, request: Message) -> tuple[dict[str, Any], Arrays]:
        commands.parse_arm_state(request.meta)
        return _arm_reply(self._built("arm_state").arm_state()), {}

    def _arm_trajectory(self, request: Message) -> tuple[dict[str, Any], Arrays]:
        wanted = commands.parse_arm_trajectory(request.meta, request.arrays, arm_spec())
        world = self._built("arm_trajectory")
        try:
            result = world.follow_trajectory(wanted.samples, wanted.dt, wanted.stop_on_contact,
                                             wanted.stop_on_new_contact)
        except ValueError as error:  # the first sample is not where the arm is
            raise RequestError(f"arm_trajectory.{error}") from None
        run = result.run
        return {
            **_arm_reply(world.arm_state()),
            "max_error": run.max_error,
            "final_error": run.final_error,
            "samples_done": run.samples_done,
            "stopped_on_contact": run.stopped_on_contact,
            "contacts": result.contacts,
        }, {}

    def _gripper(self, request: Message) -> tuple[dict[str, Any], Arrays]:
        close = commands.parse_gripper(request.meta)
        world = self._built("gripper")
        world.gripper(close)
        return _arm_reply(world.arm_state()), {}


def _arm_reply(state: ArmState) -> dict[str, Any]:
    """The arm's state as every arm command answers it."""
    return {
        "joints": list(arm_spec().names),
        "positions": state.positions.tolist(),
        "tcp_pose": state.tcp_pose.tolist(),
        "gripper_width": state.gripper_width,
        "held": state.held,
        "stowed": state.stowed,
    }


def run_world(
    namespace: str,
    listen: list[str],
    connect: list[str],
    camera: CameraConfig,
    seed: int | None,
    stop: threading.Event,
    zenoh_config: str | None = None,
) -> None:
    """Open a session on the given endpoints and serve a world until ``stop`` is set.

    Args:
        namespace: the key prefix of this run.
        listen: endpoints to listen on.
        connect: endpoints to connect to.
        camera: the head camera.
        seed: the home to reset to at start, if any.
        stop: set to stop serving.
        zenoh_config: a Zenoh configuration file (TLS, access control; docs/hosts.md), if any.

    Raises:
        EndpointError: when an endpoint or the Zenoh configuration file cannot be used.
    """
    session = open_session(listen, connect, zenoh_config)
    try:
        WorldServer(session, namespace, camera).serve(stop, seed)
    finally:
        session.close()


def end_with_parent(parent: int, stop: threading.Event, period_s: float = 0.5) -> None:
    """Set ``stop`` once this process's parent is no longer ``parent``: it has ended, and this
    process was handed to another (an orphan's parent is init or a subreaper). A parent that is
    killed (SIGKILL: an evaluation worker a scheduler ends, or whose machine runs out of memory)
    runs no cleanup, so the world sees to its own end.

    Args:
        parent: the process id of the process that started this one.
        stop: the event that ends the serving.
        period_s: how often the parent is looked at.
    """
    while not stop.wait(period_s):
        if os.getppid() != parent:
            log.warning("the process that started this world (%d) has ended; stopping", parent)
            stop.set()


def _parser() -> argparse.ArgumentParser:
    defaults = CameraConfig()
    parser = argparse.ArgumentParser(prog="homebot world", description="Serve a simulated home over Zenoh.")
    parser.add_argument("--namespace", default="homebot/default", help="key prefix of this run")
    parser.add_argument(
        "--listen", action="append", help=f"endpoint to listen on (repeatable; default {DEFAULT_LISTEN})"
    )
    parser.add_argument("--connect", action="append", default=[], help="endpoint to connect to (repeatable)")
    parser.add_argument("--seed", type=int, help="reset to this home at start")
    parser.add_argument("--parent", type=int, metavar="PID",
                        help="the process that started this world: end when it has ended, so that a world "
                             "is never left behind by one that was killed; Ctrl-C (SIGINT) is then left to it")
    parser.add_argument("--zenoh-config", metavar="FILE",
                        help="a Zenoh configuration file (JSON5): TLS with mutual authentication, access "
                             "control; its listen/connect endpoints, where it sets them, replace these "
                             "options' (docs/hosts.md)")
    parser.add_argument("--width", type=int, default=defaults.width, help="camera width in pixels")
    parser.add_argument("--height", type=int, default=defaults.height, help="camera height in pixels")
    parser.add_argument("--hfov", type=float, default=defaults.hfov_deg, help="horizontal field of view, degrees")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: serve until SIGTERM, or SIGINT unless started by a ``--parent``.

    Args:
        argv: the arguments, else the process's.

    Returns:
        The process exit status: 0, or 2 when an endpoint cannot be opened.
    """
    parser = _parser()
    args = parser.parse_args(argv)
    try:
        camera = CameraConfig(width=args.width, height=args.height, hfov_deg=args.hfov)
        Keys(args.namespace)
    except ValueError as error:
        parser.error(str(error))
    if args.seed is not None and args.seed < 0:
        parser.error(f"--seed: {args.seed} must not be negative")
    if args.zenoh_config:
        try:
            load_zenoh_config(args.zenoh_config)
        except EndpointError as error:
            parser.error(f"--zenoh-config: {error}")
    logging.basicConfig(level=logging.INFO, stream=sys.stderr, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    # A world with a parent is the parent's to stop: Ctrl-C in a terminal reaches the whole process
    # group, and a world that ended on it first would fail the episode its parent is interrupting.
    signal.signal(signal.SIGINT, signal.SIG_IGN if args.parent is not None else lambda *_: stop.set())
    if args.parent is not None:
        threading.Thread(target=end_with_parent, args=(args.parent, stop), name="parent watch", daemon=True).start()
    try:
        run_world(args.namespace, args.listen or [DEFAULT_LISTEN], args.connect, camera, args.seed, stop,
                  args.zenoh_config)
    except EndpointError as error:
        log.error("%s", error)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
