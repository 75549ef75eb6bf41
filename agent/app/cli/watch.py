"""`homebot watch`: a running agent's behaviour tree, live (`agent.app.watch`), and one-shot
control requests to it: pause, continue, step, breakpoints, injected faults (`agent.app.control_client`)."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from typing import Any

import zenoh

from worlds.bus.session import open_session
from agent.app.cli.options import DEFAULT_AGENT_ENDPOINT, Commands

_FAULTS = ("failure", "raise")


def add_command(commands: Commands) -> None:
    """Add ``watch`` and its options.

    Args:
        commands: the `homebot` parser's commands.
    """
    watch = commands.add_parser("watch", help="show a running agent's behaviour tree live, or control it")
    watch.add_argument("--connect", default=DEFAULT_AGENT_ENDPOINT, metavar="ENDPOINT",
                       help=f"the agent's listen endpoint (default {DEFAULT_AGENT_ENDPOINT})")
    watch.add_argument("--namespace", help="only this run's namespace (default: any run; to control, "
                                           "the one agent that answers)")
    watch.add_argument("--once", action="store_true", help="print one snapshot and exit")
    watch.add_argument("--json", action="store_true", help="print snapshots (or the control reply) as JSON")
    watch.add_argument("--timeout", type=float, default=30.0,
                       help="seconds to wait for a snapshot or a reply (default 30)")
    control = watch.add_mutually_exclusive_group()
    control.add_argument("--state", dest="control", action="store_const", const=("state", {}),
                         help="print whether the agent is paused, its breakpoints and faults, and exit")
    control.add_argument("--pause", dest="control", action="store_const", const=("pause", {}),
                         help="pause the agent before its next tick")
    control.add_argument("--continue", dest="control", action="store_const", const=("continue", {}),
                         help="let a paused agent run freely")
    control.add_argument("--step", dest="control", action="store_const", const=("step", {}),
                         help="run a paused agent to the next tick boundary (one tick), then pause")
    control.add_argument("--break", dest="control", metavar="NAME", type=_breakpoint(True),
                         help="pause right before the behaviour NAME ticks, every time")
    control.add_argument("--unbreak", dest="control", metavar="NAME", type=_breakpoint(False),
                         help="clear the breakpoint on NAME")
    control.add_argument("--inject", dest="control", metavar="NAME=failure|raise", type=_fault,
                         help="make NAME's next tick fail without running, or raise InjectedFault")
    watch.set_defaults(handler=_watch)


def _breakpoint(on: bool) -> Callable[[str], tuple[str, dict[str, Any]]]:
    """The argparse type of ``--break`` (``on``) or ``--unbreak``: a ``breakpoint`` request."""
    def parse(name: str) -> tuple[str, dict[str, Any]]:
        if not name:
            raise argparse.ArgumentTypeError("expected a behaviour's name")
        return "breakpoint", {"behaviour": name, "on": on}
    return parse


def _fault(text: str) -> tuple[str, dict[str, Any]]:
    """``NAME=failure`` or ``NAME=raise`` as an ``inject`` request."""
    name, _, fault = text.rpartition("=")
    if not name or fault not in _FAULTS:
        raise argparse.ArgumentTypeError(f"expected NAME=failure or NAME=raise, got {text!r}")
    return "inject", {"behaviour": name, "fault": fault}


def _watch(args: argparse.Namespace) -> int:
    session = open_session(connect=[args.connect])
    try:
        if args.control is not None:
            return _control(session, args)
        from agent.app.watch import watch

        return watch(session, args.namespace, args.once, args.json, args.timeout)
    finally:
        session.close()


def _control(session: zenoh.Session, args: argparse.Namespace) -> int:
    """Send the one control request and print the reply's state; 1 when refused or unanswered."""
    from agent.app.control_client import ControlFailed, describe, send

    verb, request = args.control
    try:
        reply = send(session, args.namespace, verb, request, args.timeout)
    except ControlFailed as error:
        print(f"homebot watch: {error}", file=sys.stderr)
        return 1
    if not reply["ok"]:
        print(f"homebot watch: the agent refused: {reply.get('error')}", file=sys.stderr)
        return 1
    print(json.dumps(reply, ensure_ascii=False) if args.json else describe(reply))
    return 0
