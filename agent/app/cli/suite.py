"""`homebot suite`: seeded scenario suites for evaluation, and the tabletop suites."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from agent.app.cli.options import Commands, count_option, seed_option
from agent.app.progress import ProgressLine
from agent.app.runtime import interrupt


def add_command(commands: Commands) -> None:
    """Add ``suite make`` and ``suite tabletop`` and their options.

    Args:
        commands: the `homebot` parser's commands.
    """
    suite = commands.add_parser("suite", help="make scenario suites")
    suites = suite.add_subparsers(dest="suite", required=True)
    make = suites.add_parser("make", help="write seeded scenarios as JSON lines, split in parts")
    make.add_argument("--n", type=count_option, required=True, help="how many scenarios in all")
    make.add_argument("--split", default=None, help="part sizes adding up to n, e.g. 300/200 (default: one part)")
    make.add_argument("--names", default="calib,test", help="part names, comma separated (default calib,test)")
    make.add_argument("--seed-base", type=seed_option, default=0, help="first seed; parts take consecutive seeds")
    make.add_argument("--out", type=Path, default=Path("suites"), help="output folder (default ./suites)")
    make.add_argument("--hidden", choices=("any", "only", "never"), default="any",
                      help="hidden-evidence questions: mixed in (default), only those, or none")
    make.add_argument("--kinds", default=None,
                      help="question categories, comma separated (default: all five in the paper's shares)")
    make.set_defaults(handler=_suite_make)
    tabletop = suites.add_parser("tabletop", help="write the five tabletop suites of interactive exploration")
    tabletop.add_argument("--out", type=Path, default=Path("suites/tabletop"), help="output folder")
    tabletop.set_defaults(handler=_suite_tabletop)


def _suite_make(args: argparse.Namespace) -> int:
    from worlds.suite import SuiteError, plan_split, write_suite

    try:
        split = [int(k) for k in args.split.split("/")] if args.split else [args.n]
    except ValueError:
        print(f"homebot suite make: --split {args.split!r}: expected sizes like 300/200", file=sys.stderr)
        return 2
    names = tuple(n.strip() for n in args.names.split(",") if n.strip()) if len(split) > 1 else ("suite",)
    try:
        parts = plan_split(args.n, split, args.seed_base, names)
    except SuiteError as error:
        print(f"homebot suite make: {error}", file=sys.stderr)
        return 2

    line = ProgressLine()

    def progress(part: str, done: int, total: int) -> None:
        line.show(f"{part}: {done}/{total} scenarios", done == total)
        interrupt.check()

    kinds = tuple(k.strip() for k in args.kinds.split(",")) if args.kinds else None
    hidden = {"any": None, "only": True, "never": False}[args.hidden]
    try:
        paths = write_suite(args.out, parts, progress, kinds=kinds, hidden=hidden)
    except SuiteError as error:
        print(f"\nhomebot suite make: {error}", file=sys.stderr)
        return 2
    for part in parts:
        print(f"{paths[part.name]}: seeds {part.seeds.start}..{part.seeds.stop - 1}")
    return 0


def _suite_tabletop(args: argparse.Namespace) -> int:
    from worlds.tabletop import write_tabletop_suites

    for path in write_tabletop_suites(args.out):
        print(path)
    return 0
