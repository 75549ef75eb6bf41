"""The picture of a run: the map the robot built, the rooms, the target and the route it drove.

What the robot made of the home (its 2D map: unknown, free, explored, occupied) is the background;
over it go what only the evaluator knows (the rooms and their names, the question's target, where
the target first came into view), from the world's episode report, and the route the base drove,
coloured from light to dark as the episode went on. The title says what was asked and how it
ended; the line under it says how far the robot got: target seen or not, rooms entered, floor seen.
"""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch, Polygon  # noqa: E402
from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar  # noqa: E402

from agent.mapping.occupancy import ExplorationMap  # noqa: E402
from agent.pose import Pose2D

UNKNOWN, FREE, EXPLORED, OCCUPIED = (0.80, 0.80, 0.80), (0.97, 0.97, 0.97), (0.74, 0.88, 0.74), (0.20, 0.22, 0.28)
ROUTE_CMAP = plt.get_cmap("Reds")
TARGET_COLOUR = "#f2b705"
START_COLOUR = "#2c7bb6"
END_COLOUR = "#8e0e14"


def save_map_png(path: Path, world_map: ExplorationMap, trajectory: list[Pose2D],
                 result: dict[str, Any]) -> None:
    """Draw the run's map to ``path``. ``result`` is the run's result (question, answer, truth,
    status, steps) with the world's episode report under ``evaluation``; where that is None the
    map and the route are drawn alone.

    Args:
        path: the image file.
        world_map: the robot's map.
        trajectory: the base's poses (x, y, yaw), in order.
        result: the run's result.
    """
    evaluation = result["evaluation"]
    fig, ax = plt.subplots(figsize=(8.5, 8.5), dpi=110)
    ax.imshow(_map_image(world_map), origin="lower", extent=world_map.spec.extent(), interpolation="nearest")
    handles: list[Any] = [Patch(color=EXPLORED, label="explored (robot's map)"),
                          Patch(color=FREE, label="free, not explored"), Patch(color=OCCUPIED, label="occupied"),
                          Patch(color=UNKNOWN, label="unknown")]
    if evaluation is not None:
        handles += _draw_rooms(ax, evaluation)
        handles += _draw_target(ax, evaluation)
    handles += _draw_route(ax, trajectory)
    _frame(ax, world_map, evaluation)
    scale = _scale_length(ax)
    ax.add_artist(AnchoredSizeBar(ax.transData, scale, f"{scale:g} m", "lower left", pad=0.6, sep=4, frameon=True,
                                  size_vertical=0.06))
    ax.set_title(_headline(result), fontsize=10, loc="left")
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.07), ncol=3, fontsize=8, frameon=False)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _map_image(world_map: ExplorationMap) -> np.ndarray:
    image = np.empty(world_map.spec.shape + (3,))
    image[:] = UNKNOWN
    image[world_map.free] = FREE
    image[world_map.free & world_map.explored] = EXPLORED
    image[world_map.occupied] = OCCUPIED
    return image


def _draw_rooms(ax: Axes, evaluation: dict[str, Any]) -> list[Any]:
    """Room outlines and names at their centres; the rooms the base entered in bold."""
    entered = set(evaluation["rooms_entered"])
    for room in evaluation["rooms"]:
        corners = np.asarray(room["polygon"], dtype=float)
        ax.add_patch(Polygon(corners, closed=True, fill=False, ec="#555555", lw=0.9, ls="--"))
        x, y = corners.mean(axis=0)
        was_in = room["name"] in entered
        ax.text(x, y, room["name"], ha="center", va="center", fontsize=9 if was_in else 8,
                weight="bold" if was_in else "normal", style="normal" if was_in else "italic",
                color="#111111" if was_in else "#555555", zorder=9,
                bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": "none", "alpha": 0.75})
    return [Line2D([], [], color="#555555", ls="--", lw=0.9, label="rooms (bold: entered)")]


def _draw_target(ax: Axes, evaluation: dict[str, Any]) -> list[Any]:
    """The question's target (a star on each thing; a room target outlined), and where the base
    stood when the target first came into view, with a dotted sight line to the nearest thing."""
    target = evaluation["target"]
    things = target["things"]
    label = f"target: {_target_name(target)}"
    xy = np.asarray([thing["xy"] for thing in things], dtype=float)
    if target["kind"] == "room":
        [room] = [room for room in evaluation["rooms"] if room["name"] == things[0]["room"]]
        ax.add_patch(Polygon(np.asarray(room["polygon"]), closed=True, fill=False, ec=TARGET_COLOUR, lw=3, zorder=6))
        handles = [Patch(fill=False, ec=TARGET_COLOUR, lw=3, label=label)]
    else:
        ax.plot(xy[:, 0], xy[:, 1], "*", ms=20, mfc=TARGET_COLOUR, mec="black", mew=1.0, zorder=6)
        handles = [Line2D([], [], marker="*", ls="none", ms=14, mfc=TARGET_COLOUR, mec="black", label=label)]
    seen = evaluation["target_seen"]
    if seen is not None:
        x, y, _ = seen["base_pose"]
        nearest = xy[np.argmin(np.hypot(xy[:, 0] - x, xy[:, 1] - y))]
        ax.plot([x, nearest[0]], [y, nearest[1]], ":", color=TARGET_COLOUR, lw=2, zorder=6)
        ax.plot(x, y, "o", ms=16, mfc="none", mec=TARGET_COLOUR, mew=3, zorder=6)
        handles.append(Line2D([], [], marker="o", ls=":", ms=11, mfc="none", mec=TARGET_COLOUR, mew=3,
                              color=TARGET_COLOUR, label=f"target first in view (step {seen['step']})"))
    return handles


def _target_name(target: dict[str, Any]) -> str:
    things = target["things"]
    if target["kind"] == "room":
        return f"the {things[0]['room']}"
    first = things[0]
    name = f"{first['colour']} {first['category']}" if len(things) == 1 else first["category"]
    return name if len(things) == 1 else f"{len(things)} × {name}"


def _draw_route(ax: Axes, trajectory: list[Pose2D]) -> list[Any]:
    """The driven route, light at the start and dark at the end, with the start and end poses."""
    if not trajectory:
        return []
    poses = np.asarray(trajectory, dtype=float)
    xy = poses[:, :2]
    if len(xy) > 1:
        segments = np.stack([xy[:-1], xy[1:]], axis=1)
        progress = np.linspace(0.35, 1.0, len(segments))
        ax.add_collection(LineCollection(segments, colors=ROUTE_CMAP(progress), linewidths=2.4, zorder=5,
                                         capstyle="round"))
    for (x, y, yaw), colour in ((poses[0], START_COLOUR), (poses[-1], END_COLOUR)):
        ax.annotate("", xy=(x + 0.6 * np.cos(yaw), y + 0.6 * np.sin(yaw)), xytext=(x, y), zorder=7,
                    arrowprops={"arrowstyle": "-|>", "color": colour, "lw": 2})
    ax.plot(*xy[0], "o", color=START_COLOUR, ms=10, mec="white", zorder=8)
    ax.plot(*xy[-1], "s", color=END_COLOUR, ms=9, mec="white", zorder=8)
    return [Line2D([], [], color=ROUTE_CMAP(0.7), lw=2.4, label="route driven (light → dark)"),
            Line2D([], [], marker="o", ls="none", color=START_COLOUR, ms=9, label="start (arrow: heading)"),
            Line2D([], [], marker="s", ls="none", color=END_COLOUR, ms=8, label="end")]


def _frame(ax: Axes, world_map: ExplorationMap, evaluation: dict[str, Any] | None) -> None:
    """Show the whole home when its rooms are known (what was missed is part of the story), else
    the part of the map the robot knows; a margin of 0.6 m around either."""
    known = world_map.free | world_map.occupied
    rows, cols = np.nonzero(known) if known.any() else (np.array([0]), np.array([0]))
    corners = world_map.spec.to_world(np.array([[rows.min(), cols.min()], [rows.max(), cols.max()]]))
    if evaluation is not None:
        rooms = np.concatenate([np.asarray(room["polygon"], dtype=float) for room in evaluation["rooms"]])
        corners = np.array([np.minimum(corners[0], rooms.min(axis=0)), np.maximum(corners[1], rooms.max(axis=0))])
    margin = 0.6
    ax.set_xlim(corners[0, 0] - margin, corners[1, 0] + margin)
    ax.set_ylim(corners[0, 1] - margin, corners[1, 1] + margin)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.tick_params(labelsize=8)


def _scale_length(ax: Axes) -> float:
    """A round scale-bar length, about a sixth of the picture's width."""
    width = abs(ax.get_xlim()[1] - ax.get_xlim()[0])
    return next((m for m in (5.0, 2.0, 1.0, 0.5) if m <= width / 6), 0.5)


def _headline(result: dict[str, Any]) -> str:
    """The question; how it ended; and, from the evaluator's report, how far the robot got."""
    verdict = result["status"]
    if verdict == "answered":
        verdict = "correct" if result["correct"] else "wrong"
    lines = [textwrap.fill(result["question"], 90),
             f"answer {result['answer'] or '—'} ({result['answer_text'] or 'none'}), truth {result['ground_truth']} "
             f"({result['ground_truth_text']}): {verdict}, {result['steps']} steps"]
    evaluation = result["evaluation"]
    if evaluation is not None:
        seen = evaluation["target_seen"]
        sight = (f"target first in view at step {seen['step']} ({100 * seen['share']:.1f} % of the frame)"
                 if seen else "target never in view")
        share = evaluation["floor_seen_m2"] / evaluation["free_floor_m2"] if evaluation["free_floor_m2"] else 0.0
        lines.append(f"{sight}; rooms entered {len(evaluation['rooms_entered'])} of {len(evaluation['rooms'])}; "
                     f"floor seen {evaluation['floor_seen_m2']:.0f} of {evaluation['free_floor_m2']:.0f} m² "
                     f"({100 * share:.0f} %)")
    return "\n".join(lines)
