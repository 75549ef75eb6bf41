"""The `homebot` command: world, run, replay, watch, inspect, bench."""

from __future__ import annotations

import argparse
import importlib
import logging
import os
import signal
import sys
import threading
from types import FrameType


def _interrupted_while_loading(signum: int, frame: FrameType | None) -> None:
    """Ctrl-C while the commands' modules load: nothing has started yet, so end at once, quietly
    (a KeyboardInterrupt would stop an import half way and print its traceback)."""
    sys.stderr.write("\nhomebot: interrupted (Ctrl-C) while starting\n")
    os._exit(128 + signal.SIGINT)


_LOADING = threading.current_thread() is threading.main_thread() and \
    signal.getsignal(signal.SIGINT) is signal.default_int_handler
if _LOADING:
    signal.signal(signal.SIGINT, _interrupted_while_loading)

from worlds.bus.session import EndpointError  # noqa: E402 (after the Ctrl-C handler above)
from agent.app.cli import bench, calibrate, eval, inspect, replay, run, skills, suite, watch  # noqa: E402
from agent.app.cli.options import INTERRUPTED  # noqa: E402
from agent.app.config import ConfigError  # noqa: E402
from agent.app.runtime import interrupt  # noqa: E402

if _LOADING:
    interrupt.install()

#: Commands with a parser of their own, handed the words after their name: command -> (the module
#: whose ``main(argv)`` runs it, the help line shown here).
DELEGATED: dict[str, tuple[str, str]] = {
    "world": ("worlds.server", "serve a simulated home over Zenoh (see `homebot world --help`)"),
    "scene": ("worlds.scene_cli", "make, draw and check scene specs (see `homebot scene --help`)"),
    "acsg": ("agent.app.cli.acsg", "retrieval plans and pictures of scene graphs (see `homebot acsg --help`)"),
    "lfe": ("agent.app.cli.lfe", "training data and training of the frontier-property network "
                                 "(see `homebot lfe --help`)"),
}


def main(argv: list[str] | None = None) -> int:
    """Run one `homebot` command.

    Args:
        argv: the words after ``homebot`` (default: the process's arguments).

    Returns:
        The exit code: 0 done, 1 the command failed, 2 bad arguments or settings, 130 ended by
        Ctrl-C (what finished is kept; each command says more in its help).
    """
    argv = sys.argv[1:] if argv is None else argv
    try:
        if argv[:1] and argv[0] in DELEGATED:
            return importlib.import_module(DELEGATED[argv[0]][0]).main(argv[1:])
        args = build_parser().parse_args(argv)
        logging.basicConfig(level=logging.DEBUG if args.verbose else logging.WARNING,
                            format="%(levelname)s %(name)s: %(message)s")
        return args.handler(args)
    except (ConfigError, EndpointError) as error:
        print(f"homebot: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        command = " ".join(word for word in argv[:2] if not word.startswith("-"))
        print(f"\nhomebot {command}: interrupted (Ctrl-C); what finished is kept", file=sys.stderr)
        return INTERRUPTED


def build_parser() -> argparse.ArgumentParser:
    """The `homebot` parser, every command on it, each with its handler as ``handler``.

    Returns:
        The parser; a parsed command line's ``handler(args)`` runs the command and returns its exit code.
    """
    parser = argparse.ArgumentParser(prog="homebot", description=__doc__)
    parser.add_argument("-v", "--verbose", action="store_true", help="log debug messages")
    commands = parser.add_subparsers(dest="command", required=True)
    for name, (_, help_line) in DELEGATED.items():
        commands.add_parser(name, help=help_line)
    for family in (run, replay, skills, watch, inspect, suite, eval, calibrate, bench):
        family.add_command(commands)
    return parser
