"""`homebot watch`: the running agents, and a running agent's behaviour tree, live (`agent.app.watch`)."""

from __future__ import annotations

import argparse
import json
import sys

from worlds.bus.session import open_session
from agent.app.agents import AgentInfo, find_agents
from agent.app.cli.options import DEFAULT_AGENT_ENDPOINT, Commands


def add_command(commands: Commands) -> None:
    """Add ``watch`` and its options.

    Args:
        commands: the `homebot` parser's commands.
    """
    watch = commands.add_parser("watch", help="list the running agents; show one's behaviour tree live")
    watch.add_argument("--connect", default=DEFAULT_AGENT_ENDPOINT, metavar="ENDPOINT",
                       help=f"an agent's listen endpoint (default {DEFAULT_AGENT_ENDPOINT}, "
                            "through which every agent of this machine is reached)")
    watch.add_argument("--list", action="store_true", help="list the running agents: run id, namespace, endpoint")
    watch.add_argument("--run", metavar="RUN_ID", help="watch this run (its id as --list shows it)")
    watch.add_argument("--namespace", help="only this run's namespace (default: any run)")
    watch.add_argument("--once", action="store_true", help="print one snapshot and exit")
    watch.add_argument("--json", action="store_true", help="print snapshots (or the list) as JSON")
    watch.add_argument("--timeout", type=float, default=30.0, help="seconds to wait for a snapshot (default 30)")
    watch.add_argument("--gather", type=float, default=1.5,
                       help="seconds --list waits for agents to announce themselves (default 1.5)")
    watch.set_defaults(handler=_watch)


def _watch(args: argparse.Namespace) -> int:
    if args.run is not None and args.namespace is not None:
        print("homebot watch: --run and --namespace: give one (a run's id names its namespace)", file=sys.stderr)
        return 2
    if not args.list and args.run is None:
        return _follow(args, args.connect, args.namespace)
    session = open_session(connect=[args.connect])
    try:
        found = find_agents(session, args.gather if args.list else args.timeout, args.run)
    finally:
        session.close()
    if args.list:
        return _list(found, args.json)
    if not found:
        print(f"homebot watch: --run {args.run}: no such agent announced itself through {args.connect} within "
              f"{args.timeout:.0f} s (`homebot watch --list` shows the running ones)", file=sys.stderr)
        return 1
    return _follow(args, found[0].endpoint, found[0].namespace)


def _list(agents: list[AgentInfo], as_json: bool) -> int:
    """Print the agents as a table, or as a JSON list of {run_id, namespace, endpoint}."""
    if as_json:
        print(json.dumps([{"run_id": a.run_id, "namespace": a.namespace, "endpoint": a.endpoint} for a in agents]))
        return 0
    if not agents:
        print("no running agents", file=sys.stderr)
        return 0
    width = max(len(a.run_id) for a in agents)
    for agent in agents:
        print(f"{agent.run_id:<{width}}  {agent.namespace}  {agent.endpoint}")
    return 0


def _follow(args: argparse.Namespace, endpoint: str, namespace: str | None) -> int:
    """Watch the snapshots under ``namespace`` (any when None) through a session connected to ``endpoint``."""
    from agent.app.watch import watch

    session = open_session(connect=[endpoint])
    try:
        return watch(session, namespace, args.once, args.json, args.timeout)
    finally:
        session.close()
