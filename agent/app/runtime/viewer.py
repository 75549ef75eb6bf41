"""Showing a recording in the Rerun viewer: spawned on this machine's display, or served as a web
viewer on a local address when there is no display.

`homebot run --viewer` streams the episode to it while it runs; `homebot replay` sends a run
folder's ``recording.rrd`` to it the same way.
"""

from __future__ import annotations

import os
import socket
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import quote

import rerun as rr
from rerun.chunk import RrdReader

RECORDING_FILE = "recording.rrd"


class ReplayError(ValueError):
    """A run folder without a readable recording; the text names the path."""


@dataclass
class LiveViewer:
    """Where a recording stream is shown as it is logged: a spawned native viewer or a web viewer.

    Args:
        web: serve a web viewer on a local address rather than spawning the native one.
    """

    web: bool
    address: str = ""  # what to open: the web viewer's address, or the spawned viewer's gRPC url
    sinks: list[Any] = field(default_factory=list)  # what feeds it, once started

    @classmethod
    def for_this_machine(cls) -> LiveViewer:
        """The native viewer where a display exists, the web viewer elsewhere.

        Returns:
            The viewer, not started yet.
        """
        return cls(web=not has_display())

    def start(self) -> list[Any]:
        """Start the viewer (a process, or a web server in this one) and return the sinks that feed it.

        Returns:
            Rerun log sinks for `rerun.RecordingStream.set_sinks`.
        """
        port = _free_port()
        if self.web:
            server = rr.GrpcServerSink(bind_ip="127.0.0.1", port=port)
            web_port = _free_port()
            rr.serve_web_viewer(web_port=web_port, open_browser=False, connect_to=server.uri)
            self.address = f"http://127.0.0.1:{web_port}/?url={quote(server.uri, safe='')}"
            self.sinks = [server]
        else:
            rr.spawn(port=port, connect=False)
            self.address = f"rerun+http://127.0.0.1:{port}/proxy"
            self.sinks = [rr.GrpcSink(self.address)]
        return self.sinks

    def describe(self) -> str:
        """One line saying where the recording is shown.

        Returns:
            The line.
        """
        if self.web:
            return f"web viewer at {self.address} (served while this process runs)"
        return f"viewer spawned, fed at {self.address}"


def has_display() -> bool:
    """Whether a native window can open here: a desktop OS, or an X or Wayland display.

    Returns:
        True when the native viewer can be spawned.
    """
    if sys.platform in ("darwin", "win32"):
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def recording_in(run_folder: Path) -> Path:
    """The run folder's recording, checked to be a Rerun recording.

    Args:
        run_folder: a run folder (or a recording file itself).

    Returns:
        The recording's path.

    Raises:
        ReplayError: no recording there, or a file Rerun cannot read, naming the path.
    """
    path = run_folder if run_folder.is_file() else run_folder / RECORDING_FILE
    if not path.is_file():
        raise ReplayError(f"{path}: no recording (episodes record unless run by an evaluation without --record)")
    try:
        if not RrdReader(path).recordings():
            raise ReplayError(f"{path}: holds no Rerun recording")
    except (OSError, ValueError, RuntimeError) as error:
        if isinstance(error, ReplayError):
            raise
        raise ReplayError(f"{path}: not a Rerun recording ({error})") from None
    return path


def replay(path: Path, viewer: LiveViewer) -> rr.RecordingStream:
    """Send a recording to a viewer started here.

    Args:
        path: the recording (checked with `recording_in`).
        viewer: the viewer to start and feed.

    Returns:
        The stream that fed it; a web viewer serves only while it and this process live.
    """
    stream = rr.RecordingStream("homebot", recording_id=path.parent.name or None, send_properties=False)
    stream.set_sinks(*viewer.start())
    rr.send_chunks(RrdReader(path).stream(), recording=stream)
    stream.flush()
    return stream


def _free_port() -> int:
    """A TCP port on the loopback nobody listens on now."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])
