"""A tabletop exploration scene as plain data, and the ground-truth scene graph it implies.

Instance ids: the table is 1, storage pieces follow, then objects, then each piece's parts and
handles (`StoragePlacement.part_ids`). The ground truth (`TabletopScene.ground_truth_acsg`) follows
RoboEXP's action-conditioned scene graph; see that method for its JSON. What blocks what is decided
from geometry, not recorded: an object blocks a part when the part, swung or pulled through its
whole range, passes through the object's box. The scenes themselves are drawn in `worlds.tabletop`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from worlds.storage_placement import StoragePlacement, part_labels
from worlds.things import Label, Rect
from worlds.urdf import sweep_points

TABLE_ID = 1
TABLE_HEIGHT = 0.75
#: Boxes put over things are open at the bottom, with walls this thick.
SHELL_WALL = 0.006


def half_extents(shape: str, dims: tuple[float, ...]) -> np.ndarray:
    """Half sizes of the axis-aligned box around a ``shape`` of ``dims`` (see `vocabulary.OBJECTS`).

    Args:
        shape: "sphere", "cylinder" or "box".
        dims: its dimensions.

    Returns:
        The half sizes (3,).
    """
    if shape == "sphere":
        return np.array([dims[0]] * 3)
    if shape == "cylinder":
        return np.array([dims[0], dims[0], dims[1] / 2])
    return np.asarray(dims[:3]) / 2


def _label(instance_id: int, category: str, colour: str) -> Label:
    """A tabletop label: what the thing looks like, as in a home (`worlds.things`)."""
    return {"id": instance_id, "category": category, "colour": colour}


@dataclass(frozen=True)
class TabletopObject:
    """A small thing. ``shape`` 'shell' is an open-bottom box (category 'box') over what is inside it.

    ``relation`` is 'on' (the table or a piece's top) or 'inside' (a storage ``slot``, or a shell);
    ``parent`` the instance id it relates to. ``dims`` as in `vocabulary.OBJECTS`, a shell's outer size.
    """

    instance_id: int
    category: str
    colour: str
    shape: str
    dims: tuple[float, ...]
    center: tuple[float, float, float]
    relation: str
    parent: int
    slot: str | None = None

    @property
    def half_extents(self) -> np.ndarray:
        return half_extents(self.shape, self.dims)

    def footprint(self) -> Rect:
        """The object's footprint on the table: (xmin, ymin, xmax, ymax).

        Returns:
            The rectangle.
        """
        (x0, y0, _), (x1, y1, _) = self.center - self.half_extents, self.center + self.half_extents
        return (float(x0), float(y0), float(x1), float(y1))


@dataclass(frozen=True)
class TabletopScene:
    """One variant: the table, its storage (colour and placement) and its objects."""

    task: str
    seed: int
    table_size: tuple[float, float]
    table_colour: str
    storage: tuple[tuple[str, StoragePlacement], ...]
    objects: tuple[TabletopObject, ...]

    def labels(self) -> dict[int, Label]:
        """Instance id -> label for the table, every piece, part, handle and object.

        Returns:
            The labels.
        """
        labels = {TABLE_ID: _label(TABLE_ID, "table", self.table_colour)}
        for colour, placement in self.storage:
            category = placement.model.model.replace("_", " ")
            labels[placement.furniture_id] = _label(placement.furniture_id, category, colour)
            labels.update({label["id"]: label for label in part_labels(placement, colour).values()})
        for obj in self.objects:
            labels[obj.instance_id] = _label(obj.instance_id, obj.category, obj.colour)
        return labels

    def blockers(self) -> list[tuple[int, int, str]]:
        """(object id, piece id, part name) for every object standing in a part's way.

        Returns:
            The blockers.
        """
        found = []
        standing = [o for o in self.objects if o.relation == "on"]
        for _, placement in self.storage:
            for part in placement.model.parts:
                points = placement.to_world(sweep_points(placement.model, part))
                for obj in standing:
                    lo, hi = obj.center - obj.half_extents + 0.003, obj.center + obj.half_extents - 0.003
                    if np.any(np.all((points > lo) & (points < hi), axis=1)):
                        found.append((obj.instance_id, placement.furniture_id, part.name))
        return found

    def ground_truth_acsg(self) -> dict[str, Any]:
        """The action-conditioned scene graph the exploration should end with, as JSON.

        ``nodes``: objects ``{"id": "o<instance>", "kind": "object", "instance", "category",
        "colour"}`` and actions ``{"id": "open:<instance>" | "pick:<instance>", "kind": "action",
        "type": "open" | "pick", "target": "o<instance>"}`` (open actions also name the ``handle``).
        ``edges``: ``{"source", "target", "type", "relation"}`` of the paper's four types.
        object-object edges run from the parent to the child and name the child's relation to it
        (on, inside, belongs: a part belongs to its piece, a handle to its part), so the graph
        is a DAG; object-action ("can be opened" / "can be picked"); action-object "reveals" (the
        objects the action makes visible, one level deep); action-action "precondition" (picking an
        obstacle away before opening the part it blocks). Pick actions exist for shells and obstacles.

        Returns:
            The graph's nodes and edges.
        """
        labels = self.labels()
        nodes: list[dict[str, Any]] = [
            {"id": f"o{i}", "kind": "object", "instance": i, "category": label["category"], "colour": label["colour"]}
            for i, label in sorted(labels.items())
        ]
        edges: list[dict[str, str]] = []

        def edge(source: str, target: str, kind: str, relation: str) -> None:
            edges.append({"source": source, "target": target, "type": kind, "relation": relation})

        def action(kind: str, target: int, **extra: str) -> str:
            name = f"{kind}:{target}"
            if all(n["id"] != name for n in nodes):
                nodes.append({"id": name, "kind": "action", "type": kind, "target": f"o{target}", **extra})
                edge(f"o{target}", name, "object-action", "can be opened" if kind == "open" else "can be picked")
            return name

        pieces = {placement.furniture_id: placement for _, placement in self.storage}
        for placement in pieces.values():
            ids = placement.part_ids()
            edge(f"o{TABLE_ID}", f"o{placement.furniture_id}", "object-object", "on")
            for part in placement.model.parts:
                edge(f"o{placement.furniture_id}", f"o{ids[part.name]}", "object-object", "belongs")
                edge(f"o{ids[part.name]}", f"o{ids[part.handle]}", "object-object", "belongs")
                action("open", ids[part.name], handle=f"o{ids[part.handle]}")
        for obj in self.objects:
            parent = obj.parent
            if obj.slot is not None:
                placement = pieces[obj.parent]
                slot = placement.model.slot(obj.slot)
                parent = placement.part_ids()[slot.part] if slot.part is not None else obj.parent
                edge(f"open:{placement.part_ids()[slot.access]}", f"o{obj.instance_id}", "action-object", "reveals")
            elif obj.relation == "inside":
                edge(action("pick", obj.parent), f"o{obj.instance_id}", "action-object", "reveals")
            edge(f"o{parent}", f"o{obj.instance_id}", "object-object", obj.relation)
        for obstacle, piece, part in self.blockers():
            edge(action("pick", obstacle), f"open:{pieces[piece].part_ids()[part]}", "action-action", "precondition")
        return {"task": self.task, "seed": self.seed, "nodes": nodes, "edges": edges}

    def to_dict(self) -> dict[str, Any]:
        """The scene as plain data, for suites.

        Returns:
            The dict.
        """
        return {
            "task": self.task,
            "seed": self.seed,
            "table": {"id": TABLE_ID, "size": list(self.table_size), "height": TABLE_HEIGHT,
                      "colour": self.table_colour},
            "storage": [{"colour": c, "placement": placement.to_dict()} for c, placement in self.storage],
            "objects": [{k: list(v) if isinstance(v, tuple) else v for k, v in vars(o).items()} for o in self.objects],
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> TabletopScene:
        """A scene read back from its `to_dict` form.

        Args:
            data: the dict.

        Returns:
            The scene.
        """
        storage = tuple((s["colour"], StoragePlacement.from_dict(s["placement"])) for s in data["storage"])
        objects = tuple(
            TabletopObject(**{**o, "dims": tuple(o["dims"]), "center": tuple(o["center"])}) for o in data["objects"]
        )
        table = data["table"]
        return cls(data["task"], int(data["seed"]), tuple(table["size"]), table["colour"], storage, objects)
