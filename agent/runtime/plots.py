"""The picture of a run: the 2D map the robot built, the path it drove, where it started and ended."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402

from agent.mapping.occupancy import ExplorationMap  # noqa: E402


def save_map_png(path: Path, world_map: ExplorationMap, trajectory: list[tuple[float, float, float]],
                 title: str) -> None:
    """Unknown grey, free light, explored green-tinted, occupied dark; path in red."""
    image = np.full(world_map.spec.shape + (3,), 0.55)
    image[world_map.free] = (0.93, 0.93, 0.93)
    image[world_map.free & world_map.explored] = (0.72, 0.88, 0.72)
    image[world_map.occupied] = (0.15, 0.15, 0.2)
    known = world_map.free | world_map.occupied
    rows, cols = np.nonzero(known) if known.any() else (np.array([0]), np.array([0]))
    fig, ax = plt.subplots(figsize=(7, 7), dpi=110)
    ax.imshow(image, origin="lower", extent=world_map.spec.extent(), interpolation="nearest")
    if trajectory:
        xy = np.asarray(trajectory)[:, :2]
        ax.plot(xy[:, 0], xy[:, 1], "-", color="#c0392b", lw=2, label="path")
        ax.plot(*xy[0], "o", color="#2c7bb6", ms=9, label="start")
        ax.plot(*xy[-1], "*", color="#c0392b", ms=14, label="end")
    margin = 1.0
    corners = world_map.spec.to_world(np.array([[rows.min(), cols.min()], [rows.max(), cols.max()]]))
    ax.set_xlim(corners[0, 0] - margin, corners[1, 0] + margin)
    ax.set_ylim(corners[0, 1] - margin, corners[1, 1] + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(title, fontsize=10)
    handles, labels = ax.get_legend_handles_labels()
    handles += [Patch(color=(0.72, 0.88, 0.72), label="explored"), Patch(color=(0.93, 0.93, 0.93), label="free"),
                Patch(color=(0.15, 0.15, 0.2), label="occupied")]
    ax.legend(handles=handles, loc="upper right", fontsize=8, framealpha=0.9)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
