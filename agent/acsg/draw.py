"""A picture of an ACSG for people: layered top-down, objects and actions told apart, edges by kind.

Layers are longest-path depths from the roots, so every edge points downwards and a chain of
reveals (a box in a box in a drawer) reads from top to bottom. Within a layer nodes are ordered by
the mean position of their parents (one barycentre pass), which keeps most edges short.
"""

from __future__ import annotations

from pathlib import Path

from agent.acsg.graph import ACSG
from agent.acsg.nodes import ActionNode
from agent.acsg.order import depths, topological_order

EDGE_COLOURS = {
    "object-object": "#4d4d4d",
    "object-action": "#1f77b4",
    "action-object": "#2ca02c",
    "action-action": "#d62728",
}
_OBJECT_STYLE = {"boxstyle": "round,pad=0.35", "facecolor": "#dbe9f6", "edgecolor": "#1f4e79"}
_ACTION_STYLE = {"boxstyle": "square,pad=0.35", "facecolor": "#fde2c8", "edgecolor": "#b35806"}


def layout(graph: ACSG) -> dict[str, tuple[float, float]]:
    """Node id -> (x, y): y is minus the depth, x the rank within the layer, centred.

    Args:
        graph: the graph.

    Returns:
        The positions.
    """
    depth = depths(graph)
    layers: dict[int, list[str]] = {}
    for node in topological_order(graph):
        layers.setdefault(depth[node], []).append(node)
    position: dict[str, tuple[float, float]] = {}
    for level in sorted(layers):
        members = layers[level]
        if level > 0:
            def barycentre(n: str) -> float:
                xs = [position[p][0] for p in graph.predecessors(n) if p in position]
                return sum(xs) / len(xs) if xs else 0.0
            members = sorted(members, key=barycentre)
        offset = (len(members) - 1) / 2
        for i, node in enumerate(members):
            position[node] = (float(i - offset), float(-level))
    return position


def _text(graph: ACSG, node_id: str) -> str:
    node = graph.node(node_id)
    if isinstance(node, ActionNode):
        return f"{node.type} {graph.object(node.target).label}\n{node.id}"
    return f"{node.label}\n{node.id}"


def draw_acsg(graph: ACSG, path: Path | str, title: str | None = None, dpi: int = 120) -> Path:
    """Write the graph to a PNG at ``path`` and return the path.

    Args:
        graph: the graph.
        path: the PNG to write.
        title: the figure's title, if any.
        dpi: the image's resolution.

    Returns:
        The path written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    pos = layout(graph)
    width = max((sum(1 for p in pos.values() if p[1] == y) for y in {p[1] for p in pos.values()}), default=1)
    depth = 1 + max((-p[1] for p in pos.values()), default=0)
    fig, ax = plt.subplots(figsize=(max(6.0, 1.6 * width), max(3.0, 1.3 * depth + 1.0)))
    for edge in graph.edges():
        (x0, y0), (x1, y1) = pos[edge.source], pos[edge.target]
        bow = 0.08 if y0 - y1 <= 1 else 0.35  # edges that skip layers bow out past the nodes between
        ax.annotate("", xy=(x1, y1), xytext=(x0, y0),
                    arrowprops={"arrowstyle": "-|>", "color": EDGE_COLOURS[edge.kind], "lw": 1.2,
                                "shrinkA": 14, "shrinkB": 14, "connectionstyle": f"arc3,rad={bow}"})
        if edge.kind == "object-object":
            # the middle of the arc (a quadratic Bezier through arc3's control point), roughly
            mid_x, mid_y = (x0 + x1) / 2 + bow * (y1 - y0) / 2, (y0 + y1) / 2 - bow * (x1 - x0) / 2
            ax.text(mid_x, mid_y, edge.relation, fontsize=6, color=EDGE_COLOURS[edge.kind],
                    ha="center", va="center", bbox={"facecolor": "white", "edgecolor": "none", "pad": 0.5})
    for node_id, (x, y) in pos.items():
        style = _ACTION_STYLE if graph.node(node_id).kind == "action" else _OBJECT_STYLE
        ax.text(x, y, _text(graph, node_id), ha="center", va="center", fontsize=7, bbox=style, zorder=3)
    handles = [Patch(**{k: v for k, v in _OBJECT_STYLE.items() if k != "boxstyle"}, label="object"),
               Patch(**{k: v for k, v in _ACTION_STYLE.items() if k != "boxstyle"}, label="action")]
    names = {"object-object": "object → object (relation)", "object-action": "object → action (can be done)",
             "action-object": "action → object (reveals)", "action-action": "action → action (precondition)"}
    handles += [Line2D([0], [0], color=colour, lw=2, label=names[kind]) for kind, colour in EDGE_COLOURS.items()]
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    xs = [p[0] for p in pos.values()] or [0.0]
    ax.set_xlim(min(xs) - 0.8, max(xs) + 0.8)
    ax.set_ylim(-depth + 0.4, 0.6)
    ax.set_axis_off()
    if title:
        ax.set_title(title, fontsize=9)
    path = Path(path)
    fig.savefig(path, dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    return path
