"""The `homebot acsg` commands, as a function the main CLI can hand its words to.

- ``acsg plan FILE OBJECT [--seed N]`` prints the steps to fetch OBJECT (an id like ``o7``, an
  instance id, a label, or colour and label), one per line;
- ``acsg show FILE [--out PNG] [--seed N]`` draws the graph (default: FILE with ``.png``).

FILE is an ACSG in our JSON, a ground-truth graph, a suite record, or a suite's JSON lines
(``--seed`` picks the record). `main(argv)` takes the words after ``acsg`` and returns the exit
code: 0 done, 1 the file or the object is wrong, 2 bad arguments.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from agent.acsg.draw import draw_acsg
from agent.acsg.json_format import load_acsg
from agent.acsg.nodes import ACSGError
from agent.acsg.plan import retrieval_plan


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="homebot acsg", description="action-conditioned scene graphs")
    commands = parser.add_subparsers(dest="command", required=True)
    plan = commands.add_parser("plan", help="the actions that fetch an object, in order")
    plan.add_argument("file", type=Path, help="ACSG JSON, ground truth, suite record or suite .jsonl")
    plan.add_argument("object", help="object id (o7), instance id, label, or 'colour label'")
    plan.add_argument("--seed", type=int, help="which record of a suite's .jsonl")
    show = commands.add_parser("show", help="draw the graph to a PNG")
    show.add_argument("file", type=Path, help="ACSG JSON, ground truth, suite record or suite .jsonl")
    show.add_argument("--out", type=Path, help="PNG to write (default: FILE with .png)")
    show.add_argument("--seed", type=int, help="which record of a suite's .jsonl")
    return parser


def main(argv: list[str] | None = None) -> int:
    """``homebot acsg``: load a scene graph and print, plan or draw it.

    Args:
        argv: the command line's arguments (``sys.argv[1:]`` when None).

    Returns:
        The exit status: 0 on success.
    """
    try:
        args = _parser().parse_args(argv)
    except SystemExit as exit_:
        return int(exit_.code or 0)
    try:
        graph = load_acsg(args.file, args.seed)
        if args.command == "plan":
            for number, step in enumerate(retrieval_plan(graph, args.object), start=1):
                print(f"{number}. {step}")
            return 0
        out = args.out or args.file.with_suffix(".png")
        title = " ".join(str(graph.meta[k]) for k in ("task", "seed") if k in graph.meta) or args.file.name
        print(f"wrote {draw_acsg(graph, out, title=title)}")
        return 0
    except ACSGError as error:
        print(f"homebot acsg {args.command}: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
