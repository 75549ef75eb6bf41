"""Starting a world server as a child process (the embedded default of `homebot run`)."""

from __future__ import annotations

import logging
import os
import shlex
import signal
import subprocess
import sys
import time
from pathlib import Path

from agent.app.config import CameraSettings
from worlds.bus.link import WorldLink
from worlds.bus.liveness import describe_exit, refused

log = logging.getLogger(__name__)


class WorldStartError(RuntimeError):
    """The world process did not come up; the text carries the end of its log."""


class WorldProcess:
    """A `worlds.server` child listening on ``endpoint`` under ``namespace``; its log goes to a file,
    which starts with the command that started it, so a world that ends before it writes a line
    still leaves one (its Python output is unbuffered, so nothing it wrote is lost if it is killed).
    The world ends with this process (``--parent``): one whose parent is killed is not left behind.

    Args:
        namespace: the bus namespace.
        endpoint: the endpoint the world listens on.
        camera: the head camera's settings.
        log_path: the world's log file.
        connect: endpoints the world connects to (the agent's, listening already: the two meet as
            soon as the world is up, with no retries on either side).
        seed: the home it builds at start, before it answers (a first reset to just this seed is
            answered with it).
        zenoh_config: a Zenoh configuration file its session opens with ("": none).
    """

    def __init__(self, namespace: str, endpoint: str, camera: CameraSettings, log_path: Path,
                 connect: list[str] | None = None, seed: int | None = None, zenoh_config: str = "") -> None:
        self.log_path = log_path
        self.endpoint = endpoint
        command = [
            sys.executable, "-m", "worlds.server",
            "--namespace", namespace,
            "--listen", endpoint,
            "--parent", str(os.getpid()),
            *(word for other in connect or [] for word in ("--connect", other)),
            *(("--seed", str(seed)) if seed is not None else ()),
            *(("--zenoh-config", zenoh_config) if zenoh_config else ()),
            "--width", str(camera.width),
            "--height", str(camera.height),
            "--hfov", str(camera.hfov_deg),
        ]
        log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log_file = open(log_path, "wb")
        self._log_file.write(f"$ {shlex.join(command)}\n".encode())
        self._log_file.flush()  # before the child appends to the same file
        self.process = subprocess.Popen(command, stdout=self._log_file, stderr=subprocess.STDOUT,
                                        stdin=subprocess.DEVNULL, env={**os.environ, "PYTHONUNBUFFERED": "1"})

    def wait_ready(self, link: WorldLink, timeout_s: float) -> None:
        """Wait for the world's liveliness token; raise WorldStartError if it exits or is too slow.

        Args:
            link: the link to the world.
            timeout_s: how long to wait.

        Raises:
            WorldStartError: the process exited or was too slow.
        """
        waited = 0.0
        while not link.liveness.wait_alive(0.2):
            waited += 0.2
            code = self.process.poll()
            if code is not None:
                raise WorldStartError(f"the world process ended before it came up: {describe_exit(code)}; "
                                      f"{self.describe_log()}")
            if waited >= timeout_s:
                raise WorldStartError(f"the world process did not come up within {timeout_s:.0f} s; "
                                      f"{self.describe_log()}")

    def wait_listening(self, timeout_s: float) -> None:
        """Wait until the world accepts connections at its endpoint (for an agent that joins it
        rather than waiting for its token); raise WorldStartError if it has ended or is too slow.

        Args:
            timeout_s: how long to wait.

        Raises:
            WorldStartError: the process has ended, or does not listen in time.
        """
        deadline = time.monotonic() + timeout_s
        while refused(self.endpoint) is not None:
            code = self.process.poll()
            if code is not None:
                raise WorldStartError(f"the world process has ended: {describe_exit(code)}; {self.describe_log()}")
            if time.monotonic() >= deadline:
                raise WorldStartError(f"the world process did not listen at {self.endpoint} within {timeout_s:.0f} s; "
                                      f"{self.describe_log()}")
            time.sleep(0.1)

    def describe_log(self, lines: int = 20) -> str:
        """Where the world's log is and its last lines, to end a message with.

        Args:
            lines: how many lines.

        Returns:
            ``the end of its log (PATH):`` and the lines, each on its own line.
        """
        return f"the end of its log ({self.log_path}):\n{self.log_tail(lines)}"

    def log_tail(self, lines: int = 20) -> str:
        """The last lines of the world's log: the command that started it, then what it wrote.

        Args:
            lines: how many lines.

        Returns:
            The lines.
        """
        text = self.log_path.read_bytes().decode(errors="replace").splitlines()
        if len(text) <= 1:
            text.append("(the world wrote nothing before it ended)" if self.process.poll() is not None
                        else "(the world has written nothing yet)")
        return "\n".join(text[-lines:])

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop the world process: SIGTERM (and SIGCONT, for a world that was stopped), then
        SIGKILL if it does not exit in time.

        Args:
            timeout_s: how long it may take to exit.
        """
        if self.process.poll() is None:
            self.process.terminate()
            self.process.send_signal(signal.SIGCONT)
            try:
                self.process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                log.warning("world process ignored SIGTERM; killing it")
                self.process.kill()
                self.process.wait()
        self._log_file.close()
