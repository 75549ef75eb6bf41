"""A top-down picture of a home, for people: rooms, walls, doorways, furniture, storage, objects.

Rooms are tinted with their floor colour and named; walls are dark, doorways dashed; furniture is
drawn in its colour and named. Storage furniture has a blue outline and a thick front edge, and its
open parts show: an open door as a swung leaf with its arc, an open drawer or flap pulled out.
Switches show too: a lit lamp glows, a lit TV screen is blue, hot burners are red, a closed curtain
covers its window. Objects are dots in their colour with their category beside them; the marker
tells where they are (a circle on a top or the floor, a square inside something, a triangle under a
cover). A scale bar in metres sits under the plan.
"""

from __future__ import annotations

import math
from pathlib import Path

from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Arc, Circle, Rectangle

from worlds.appearance import COLD_BURNER, DARK_SCREEN, HOT_BURNER, LIT_SCREEN, LIT_SHADE, WINDOW, is_on
from worlds.fronts import rect_to_world, to_world, world_size
from worlds.home import HomeSpec
from worlds.storage import Part
from worlds.things import Furniture, Rect, point_rect_distance
from worlds.vocabulary import COLOURS

#: Inches of figure per metre of home, and the resolution of the written PNG.
SCALE_IN_PER_M = 0.62
DPI = 140
_WALL = "#3b3b3b"
_STORAGE_EDGE = "#1f4e9c"
_MARKERS = {"on": "o", "floor": "o", "inside": "s", "under": "^"}


def _rgb(colour: str) -> tuple[float, float, float]:
    return COLOURS[colour][:3]


def _tint(colour: str, amount: float) -> tuple[float, float, float]:
    return tuple(c * amount + (1 - amount) for c in _rgb(colour))  # type: ignore[return-value]


def _ink(colour: str) -> str:
    """Black or white, whichever reads better on ``colour``."""
    r, g, b = _rgb(colour)
    return "white" if 0.3 * r + 0.59 * g + 0.11 * b < 0.45 else "black"


def _rect(ax: Axes, rect: Rect, **style: object) -> None:
    ax.add_patch(Rectangle((rect[0], rect[1]), rect[2] - rect[0], rect[3] - rect[1], **style))


def draw_home(home: HomeSpec, path: str | Path) -> Path:
    """Write the picture of ``home`` to ``path`` (PNG) and return the path.

    Args:
        home: the home.
        path: the PNG file.

    Returns:
        The path.
    """
    x0, y0, x1, y1 = home.bounds
    fig = Figure(figsize=((x1 - x0 + 1.6) * SCALE_IN_PER_M, (y1 - y0 + 2.6) * SCALE_IN_PER_M))
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(x0 - 0.8, x1 + 0.8)
    ax.set_ylim(y0 - 1.6, y1 + 1.0)
    ax.set_aspect("equal")
    ax.axis("off")
    for room in home.rooms:
        _rect(ax, room.rect, facecolor=_tint(room.floor_colour, 0.22), edgecolor="none", zorder=0)
        cx, cy = _label_spot(room.rect, [f.footprint for f in home.furniture if f.room == room.name])
        ax.text(cx, cy + 0.12, room.name, ha="center", va="bottom", fontsize=9, weight="bold", color="#333", zorder=6)
        ax.text(cx, cy, f"{room.area_m2:.1f} m²", ha="center", va="top", fontsize=6.5, color="#555", zorder=6)
    for wall in home.walls:
        _rect(ax, wall.footprint, facecolor=_WALL, edgecolor="none", zorder=4)
    for door in home.doorways:
        (dx, dy), half = door.center, door.width / 2
        xs, ys = ((dx - half, dx + half), (dy, dy)) if door.along == "x" else ((dx, dx), (dy - half, dy + half))
        ax.plot(xs, ys, linestyle=(0, (2, 1.5)), color="#b5651d", linewidth=1.2, zorder=5)
    for piece in home.furniture:
        _furniture(ax, piece)
    _objects(ax, home)
    _scale_bar(ax, x0, y0 - 1.0)
    storage = sum(piece.storage is not None for piece in home.furniture)
    ax.text(x0, y1 + 0.45, f"seed {home.seed} · {len(home.rooms)} rooms · {home.area_m2:.0f} m² · "
            f"{len(home.furniture)} furniture ({storage} storage) · {len(home.objects)} objects",
            fontsize=10, va="center", color="#222")
    _legend(ax)
    out = Path(path)
    fig.savefig(out, dpi=DPI, facecolor="white")  # a bare Figure: no pyplot state, no GUI backend
    return out


def _furniture(ax: Axes, piece: Furniture) -> None:
    storage = piece.storage is not None
    edge = _STORAGE_EDGE if storage else "#555"
    _rect(ax, piece.footprint, facecolor=_tint(piece.colour, 0.85), edgecolor=edge,
          linewidth=1.3 if storage else 0.6, zorder=2)
    width, depth, _ = world_size(piece.size, piece.facing)
    if storage:
        (ax_, ay), (bx, by) = (to_world(piece.center, piece.facing, s * width / 2, -depth / 2) for s in (-1, 1))
        ax.plot((ax_, bx), (ay, by), color=_STORAGE_EDGE, linewidth=2.2, zorder=3, solid_capstyle="butt")
        for part in piece.storage.parts:  # type: ignore[union-attr]
            _part(ax, piece, part, depth)
    _switches(ax, piece, width, depth)
    fx0, fy0, fx1, fy1 = piece.footprint
    upright = (fy1 - fy0) > 1.3 * (fx1 - fx0)
    ax.text((fx0 + fx1) / 2, (fy0 + fy1) / 2, piece.category, ha="center", va="center", fontsize=5.5,
            rotation=90 if upright else 0, color=_ink(piece.colour) if piece.colour != "white" else "#222", zorder=7)


def _part(ax: Axes, piece: Furniture, part: Part, depth: float) -> None:
    """An open part as seen from above: a swung door leaf with its arc, a pulled drawer or flap."""
    opening = piece.joints.get(part.name, 0.0)
    if opening <= 0.0:
        return
    x0, z0, x1, z1 = part.front
    face = -depth / 2
    style = dict(facecolor=(1.0, 0.85, 0.3, 0.55), edgecolor="#b8860b", linewidth=0.8, zorder=3)
    if part.kind == "drawer":
        _rect(ax, rect_to_world(piece.center, piece.facing, (x0, face - opening, x1, face)), **style)
        return
    if part.kind == "flap":
        out = (z1 - z0) * math.sin(opening)
        _rect(ax, rect_to_world(piece.center, piece.facing, (x0, face - out, x1, face)), **style)
        return
    width = x1 - x0
    hinge_x, sign = (x0, 1.0) if part.hinge == "left" else (x1, -1.0)
    tip = (hinge_x + sign * width * math.cos(opening), face - width * math.sin(opening))
    hx, hy = to_world(piece.center, piece.facing, hinge_x, face)
    tx, ty = to_world(piece.center, piece.facing, *tip)
    ax.plot((hx, tx), (hy, ty), color="#b8860b", linewidth=1.6, zorder=3)
    start = math.degrees(math.atan2(ty - hy, tx - hx))
    closed = to_world(piece.center, piece.facing, hinge_x + sign * width, face)
    end = math.degrees(math.atan2(closed[1] - hy, closed[0] - hx))
    low, high = sorted((start, end))
    if high - low > 180:
        low, high = high, low + 360
    ax.add_patch(Arc((hx, hy), 2 * width, 2 * width, theta1=low, theta2=high, color="#b8860b",
                     linewidth=0.6, linestyle=":", zorder=3))


def _switches(ax: Axes, piece: Furniture, width: float, depth: float) -> None:
    """Lamps glow, screens light up, burners glow red, curtains cover or bare their window."""
    cx, cy = piece.center[0], piece.center[1]
    if piece.category == "lamp":
        if is_on(piece.state):
            ax.add_patch(Circle((cx, cy), 0.45, facecolor=(*LIT_SHADE[:3], 0.6), edgecolor="none", zorder=1))
        ax.add_patch(Circle((cx, cy), min(width, depth) / 2, facecolor=LIT_SHADE if is_on(piece.state)
                            else _tint(piece.colour, 0.8), edgecolor="#555", linewidth=0.6, zorder=3))
    elif piece.category == "tv":
        screen = LIT_SCREEN if is_on(piece.state) else DARK_SCREEN
        _rect(ax, rect_to_world(piece.center, piece.facing, (-width / 2, -depth / 2 + 0.08, width / 2,
                                                             -depth / 2 + 0.2)), facecolor=screen, zorder=3)
    elif piece.category == "stove":
        burner = HOT_BURNER if is_on(piece.state) else COLD_BURNER
        for bx in (-width / 4, width / 4):
            for by in (-depth / 4, depth / 4):
                ax.add_patch(Circle(to_world(piece.center, piece.facing, bx, by), 0.08, facecolor=burner, zorder=3))
    elif piece.category == "curtain":
        window = (-width / 2, depth / 2 - 0.03, width / 2, depth / 2 + 0.06)
        _rect(ax, rect_to_world(piece.center, piece.facing, window), facecolor=WINDOW, edgecolor="none", zorder=5)
        if piece.state.get("curtain") == "closed":
            spans = [(-width / 2, width / 2)]
        else:
            spans = [(-width / 2, -0.32 * width), (0.32 * width, width / 2)]
        for a, b in spans:
            _rect(ax, rect_to_world(piece.center, piece.facing, (a, -depth / 2 - 0.04, b, depth / 2 - 0.03)),
                  facecolor=_rgb(piece.colour), edgecolor="#333", linewidth=0.4, zorder=5)


def _objects(ax: Axes, home: HomeSpec) -> None:
    for item in home.objects:
        x, y, _ = item.center
        ax.scatter([x], [y], s=14, marker=_MARKERS[item.relation], c=[_rgb(item.colour)], edgecolors="black",
                   linewidths=0.4, zorder=8)
        ax.text(x + 0.07, y + 0.05, item.category, fontsize=4.4, color="#222", zorder=8)


def _scale_bar(ax: Axes, x: float, y: float) -> None:
    for k in range(3):
        _rect(ax, (x + k, y, x + k + 1, y + 0.12), facecolor="black" if k % 2 == 0 else "white",
              edgecolor="black", linewidth=0.6, zorder=6)
        ax.text(x + k, y - 0.1, str(k), ha="center", va="top", fontsize=7)
    ax.text(x + 3, y - 0.1, "3 m", ha="center", va="top", fontsize=7)


def _legend(ax: Axes) -> None:
    markers = (("o", "on a top / the floor"), ("s", "inside"), ("^", "under a cover"))
    handles = [Line2D([], [], marker=m, linestyle="none", markerfacecolor="white", markeredgecolor="black",
                      label=text) for m, text in markers]
    handles += [Line2D([], [], color=_STORAGE_EDGE, linewidth=2.2, label="storage front"),
                Line2D([], [], color="#b8860b", linewidth=1.6, label="open door / drawer")]
    ax.legend(handles=handles, loc="lower right", ncol=3, fontsize=7, frameon=False)


def _label_spot(rect: Rect, footprints: list[Rect]) -> tuple[float, float]:
    """Where a room's name reads best: the point near the middle farthest from its furniture."""
    cx, cy = (rect[0] + rect[2]) / 2, (rect[1] + rect[3]) / 2
    best, best_score = (cx, cy), -math.inf
    for fx in (0.2, 0.35, 0.5, 0.65, 0.8):
        for fy in (0.25, 0.4, 0.5, 0.6, 0.75):
            x, y = rect[0] + fx * (rect[2] - rect[0]), rect[1] + fy * (rect[3] - rect[1])
            clear = min((point_rect_distance(x, y, f) for f in footprints), default=5.0)
            score = min(clear, 1.2) - 0.15 * math.hypot(x - cx, y - cy)
            if score > best_score:
                best, best_score = (x, y), score
    return best
