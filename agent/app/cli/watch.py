"""`homebot watch`: a running agent's behaviour tree, live (`agent.app.watch`)."""

from __future__ import annotations

import argparse

from worlds.bus.session import open_session
from agent.app.cli.options import DEFAULT_AGENT_ENDPOINT, Commands


def add_command(commands: Commands) -> None:
    """Add ``watch`` and its options.

    Args:
        commands: the `homebot` parser's commands.
    """
    watch = commands.add_parser("watch", help="show a running agent's behaviour tree live")
    watch.add_argument("--connect", default=DEFAULT_AGENT_ENDPOINT, metavar="ENDPOINT",
                       help=f"the agent's listen endpoint (default {DEFAULT_AGENT_ENDPOINT})")
    watch.add_argument("--namespace", help="only this run's namespace (default: any run)")
    watch.add_argument("--once", action="store_true", help="print one snapshot and exit")
    watch.add_argument("--json", action="store_true", help="print snapshots as JSON")
    watch.add_argument("--timeout", type=float, default=30.0, help="seconds to wait for a snapshot (default 30)")
    watch.set_defaults(handler=_watch)


def _watch(args: argparse.Namespace) -> int:
    from agent.app.watch import watch

    session = open_session(connect=[args.connect])
    try:
        return watch(session, args.namespace, args.once, args.json, args.timeout)
    finally:
        session.close()
