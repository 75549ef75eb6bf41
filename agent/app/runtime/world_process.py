"""Starting a world server as a child process (the embedded default of `homebot run`)."""

from __future__ import annotations

import logging
import subprocess
import sys
from pathlib import Path

from agent.app.config import CameraSettings
from worlds.bus.link import WorldLink

log = logging.getLogger(__name__)


class WorldStartError(RuntimeError):
    """The world process did not come up; the text carries the end of its log."""


class WorldProcess:
    """A `worlds.server` child listening on ``endpoint`` under ``namespace``; its log goes to a file.

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
        command = [
            sys.executable, "-m", "worlds.server",
            "--namespace", namespace,
            "--listen", endpoint,
            *(word for other in connect or [] for word in ("--connect", other)),
            *(("--seed", str(seed)) if seed is not None else ()),
            *(("--zenoh-config", zenoh_config) if zenoh_config else ()),
            "--width", str(camera.width),
            "--height", str(camera.height),
            "--hfov", str(camera.hfov_deg),
        ]
        log_path.parent.mkdir(parents=True, exist_ok=True)
        self._log_file = open(log_path, "wb")
        self.process = subprocess.Popen(command, stdout=self._log_file, stderr=subprocess.STDOUT,
                                        stdin=subprocess.DEVNULL)

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
            if self.process.poll() is not None:
                raise WorldStartError(f"the world process exited with code {self.process.returncode}:\n{self.log_tail()}")
            if waited >= timeout_s:
                raise WorldStartError(f"the world process did not come up within {timeout_s:.0f} s:\n{self.log_tail()}")

    def log_tail(self, lines: int = 20) -> str:
        """The last lines the world process wrote to its log.

        Args:
            lines: how many lines.

        Returns:
            The lines.
        """
        self._log_file.flush()
        text = self.log_path.read_text(errors="replace").splitlines()
        return "\n".join(text[-lines:])

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop the world process: SIGTERM, then SIGKILL if it does not exit in time.

        Args:
            timeout_s: how long it may take to exit.
        """
        if self.process.poll() is None:
            self.process.terminate()
            try:
                self.process.wait(timeout_s)
            except subprocess.TimeoutExpired:
                log.warning("world process ignored SIGTERM; killing it")
                self.process.kill()
                self.process.wait()
        self._log_file.close()
