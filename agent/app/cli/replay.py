"""`homebot replay`: open a run folder's Rerun recording in the viewer."""

from __future__ import annotations

import argparse
import sys
import threading
from pathlib import Path

from agent.app.cli.options import Commands


def add_command(commands: Commands) -> None:
    """Add ``replay`` and its argument.

    Args:
        commands: the `homebot` parser's commands.
    """
    replay = commands.add_parser("replay", help="open a run folder's recording (recording.rrd) in the Rerun viewer")
    replay.add_argument("run_dir", type=Path, help="a run folder (or a .rrd file)")
    replay.set_defaults(handler=_replay)


def _replay(args: argparse.Namespace) -> int:
    from agent.app.runtime.viewer import LiveViewer, ReplayError, recording_in, replay

    try:
        path = recording_in(args.run_dir)
    except ReplayError as error:
        print(f"homebot replay: {error}", file=sys.stderr)
        return 2
    viewer = LiveViewer.for_this_machine()
    stream = replay(path, viewer)
    print(f"homebot replay: {path}: {viewer.describe()}", flush=True)
    if viewer.web:
        print("press Ctrl-C to stop serving", flush=True)
        try:
            threading.Event().wait()
        except KeyboardInterrupt:
            pass
    stream.disconnect()
    return 0
