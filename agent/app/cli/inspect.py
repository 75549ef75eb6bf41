"""`homebot inspect`: a behaviour-tree inspector in the browser (`agent.app.inspector`)."""

from __future__ import annotations

import argparse
import json
import sys
import threading
from pathlib import Path

from worlds.bus.keys import check_namespace
from worlds.bus.session import open_session
from agent.app.agents import AgentInfo, find_agents
from agent.app.cli.options import DEFAULT_AGENT_ENDPOINT, Commands, add_zenoh_config_option


def add_command(commands: Commands) -> None:
    """Add ``inspect`` and its options.

    Args:
        commands: the `homebot` parser's commands.
    """
    inspect = commands.add_parser("inspect", help="inspect an agent's behaviour tree in the browser, live or recorded")
    inspect.add_argument("run_dir", nargs="?", type=Path, metavar="RUN_DIR",
                         help="a recorded run's folder (with snapshots.jsonl); without it, a live agent")
    inspect.add_argument("--connect", metavar="ENDPOINT",
                         help=f"a live agent's listen endpoint (default {DEFAULT_AGENT_ENDPOINT})")
    inspect.add_argument("--namespace", help="the live agent's namespace (default: the first agent heard)")
    inspect.add_argument("--run", metavar="RUN_ID", help="the live agent of this run (`homebot watch --list` shows "
                                                         "the running ones)")
    inspect.add_argument("--timeout", type=float, default=30.0,
                         help="seconds to wait for the agent of --run to announce itself (default 30)")
    inspect.add_argument("--host", default="127.0.0.1", help="the address the page is served on (default 127.0.0.1)")
    inspect.add_argument("--port", type=int, default=0, help="the page's port (default: any free one)")
    add_zenoh_config_option(inspect)
    inspect.set_defaults(handler=_inspect)


def _inspect(args: argparse.Namespace) -> int:
    from agent.app.inspector.history import History
    from agent.app.inspector.server import Inspector
    from agent.app.inspector.sources import LiveAgent, load_run
    from agent.app.tree_state import SnapshotError

    if args.run_dir is not None and (args.connect or args.namespace or args.run):
        print("homebot inspect: RUN_DIR: give a run folder or --connect/--namespace/--run, not both", file=sys.stderr)
        return 2
    if args.run and args.namespace:
        print("homebot inspect: --run and --namespace: give one (a run's id names its namespace)", file=sys.stderr)
        return 2
    if args.namespace:
        check_namespace(args.namespace)
    history = History()
    session = agent = None
    if args.run_dir is not None:
        try:
            load_run(args.run_dir, history)
        except (FileNotFoundError, SnapshotError) as error:
            print(f"homebot inspect: {error}", file=sys.stderr)
            return 2
        result_path = args.run_dir / "result.json"
        result = json.loads(result_path.read_text()) if result_path.is_file() else None
        server = Inspector(history, {"mode": "recorded", "source": str(args.run_dir)}, result=result,
                           host=args.host, port=args.port)
    else:
        endpoint, namespace = args.connect or DEFAULT_AGENT_ENDPOINT, args.namespace
        if args.run:
            found = _announced(endpoint, args.run, args.timeout, args.zenoh_config)
            if found is None:
                print(f"homebot inspect: --run {args.run}: no such agent announced itself through {endpoint} "
                      f"within {args.timeout:.0f} s (`homebot watch --list` shows the running ones)", file=sys.stderr)
                return 1
            endpoint, namespace = found.endpoint, found.namespace
        session = open_session(connect=[endpoint], zenoh_config=args.zenoh_config)
        agent = LiveAgent(session, namespace, history)
        server = Inspector(history, {"mode": "live", "source": f"{endpoint} {namespace or '(any namespace)'}"},
                           controller=agent.control, result=lambda: agent.outcome, host=args.host, port=args.port)
    print(f"homebot inspect: open {server.start()}  (Ctrl-C stops)", flush=True)
    try:
        threading.Event().wait()
    except KeyboardInterrupt:
        pass
    finally:
        server.close()
        if agent is not None:
            agent.close()
        if session is not None:
            session.close()
    return 0


def _announced(endpoint: str, run_id: str, timeout_s: float, zenoh_config: str | None) -> AgentInfo | None:
    """The agent of ``run_id`` as it announced itself through ``endpoint``, or None."""
    session = open_session(connect=[endpoint], zenoh_config=zenoh_config)
    try:
        found = find_agents(session, timeout_s, run_id)
    finally:
        session.close()
    return found[0] if found else None
