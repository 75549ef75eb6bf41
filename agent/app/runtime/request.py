"""What one episode asks for (`RunRequest`), its run id, and since when its start-up counts.

Light to import (no tree, no map, no model), so that `homebot run` can start the world before it
loads the rest of the runtime (`agent.app.runtime.episode_bus`).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from agent.app.config import Config

if TYPE_CHECKING:
    from agent.app.runtime.viewer import LiveViewer

DEFAULT_NAMESPACE = "homebot/default"


@dataclass(frozen=True)
class RunRequest:
    """One episode to run: its seed and settings, the scenario or scene (None: the seed's own),
    where results go, which world (``connect``: a running world's endpoint; None spawns one), and
    ``started_at``, the time (epoch s) its start-up counts from: the result's ``startup_s`` is
    from then to the first observation (None: from when the episode is asked to run)."""

    seed: int
    config: Config
    out_root: Path = Path("runs")
    connect: str | None = None  # a running world's endpoint; None spawns one
    namespace: str | None = None
    run_id: str | None = None
    scenario: dict[str, Any] | None = None  # a suite's scenario; None lets the world draw one from the seed
    scene: dict[str, Any] | None = None  # a scene spec; None lets the world generate the seed's home
    save_map: bool = True  # the map picture costs ~0.3 s; evaluations of many episodes skip it
    record: bool = True  # write recording.rrd (agent.app.runtime.recording); evaluations keep none unless asked
    viewer: LiveViewer | None = None  # a started viewer the recording streams to as it is written
    started_at: float | None = None


def new_run_id(seed: int) -> str:
    """A run id that sorts by time and names the seed: ``<date>-<time>-seed<seed>-<4 hex digits>``.

    Args:
        seed: the episode's seed.

    Returns:
        The id.
    """
    return f"{time.strftime('%Y%m%d-%H%M%S')}-seed{seed}-{os.urandom(2).hex()}"


def process_started_at() -> float:
    """When this process started (epoch s), interpreter start-up included: from ``/proc/self/stat``
    where there is one, else now.

    Returns:
        The time.
    """
    try:
        fields = Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()
        uptime = float(Path("/proc/uptime").read_text().split()[0])
    except (OSError, IndexError, ValueError):
        return time.time()
    age = uptime - int(fields[19]) / os.sysconf("SC_CLK_TCK")  # field 22, starttime, in clock ticks
    return time.time() - max(age, 0.0)
