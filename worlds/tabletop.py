"""Tabletop interactive-exploration suites after RoboEXP's Table I: drawing, building, writing.

Five tasks (`TASKS`), any number of variants each (one per seed), varying object number, type and
layout as the paper's do: storage with drawers only, with doors only, with both; nested containers
(Matryoshka-style: an open-bottom box over a smaller box or thing, in storage or on the table); and
occlusion (an obstacle standing in a door's swing, to be picked away before the door can open).
The table is centred on the world origin, long side along x; storage stands along its back edge
(+y) with fronts facing -y, towards a robot in front of the table (y < 0). Every part starts closed.
Things on the table stay out of every part's reach, except the obstacles the occlusion task puts
there on purpose; the ground truth finds blockers from geometry either way.

The seeds are split once (`worlds.tabletop_splits.SPLITS`): tuning seeds, traced and tuned on, and
reported seeds, far from them, run only whole for the figure.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from worlds.camera import SegLabels
from worlds.scene import add_boxes, add_shape, add_storage
from worlds.storage import HANDLE_REACH, storage_model
from worlds.storage_placement import StoragePlacement
from worlds.tabletop_splits import SPLITS
from worlds.tabletop_scene import SHELL_WALL, TABLE_HEIGHT, TABLE_ID, TabletopObject, TabletopScene, half_extents
from worlds.things import Rect, rects_overlap
from worlds.urdf import sweep_points
from worlds.vocabulary import COLOURS, OBJECTS

TASKS = ("drawer-only", "door-only", "drawer-door", "recursive", "occlusion")


#: Variants per task of the tuning split: the suites `write_tabletop_suites` writes.
VARIANTS = SPLITS["tuning"].variants
#: Small things that hide in storage, stand on the table or sit under a box (vocabulary words only).
_ITEMS = tuple(c for c in ("apple", "cup", "can", "jar", "mug", "soap", "bowl", "book", "clock") if c in OBJECTS)
#: Tall, narrow things that make good obstacles in front of a door (the paper's condiment bottle).
_OBSTACLES = tuple(c for c in ("bottle", "jar", "can", "milk carton", "shampoo") if c in OBJECTS)
_PAINTS = ("white", "black", "brown", "grey", "blue", "green")
_STORAGE = {  # tabletop sizes (width, depth, height) ranges per model
    "drawer_chest": ((0.3, 0.28, 0.32), (0.45, 0.34, 0.5)),
    "cabinet": ((0.34, 0.28, 0.36), (0.5, 0.35, 0.5)),
    "nightstand": ((0.38, 0.3, 0.42), (0.5, 0.38, 0.55)),
}
_TASK_STORAGE = {
    "drawer-only": (("drawer_chest",), ("drawer_chest", "drawer_chest")),
    "door-only": (("cabinet",), ("cabinet", "cabinet")),
    "drawer-door": (("nightstand",), ("drawer_chest", "cabinet"), ("cabinet", "drawer_chest")),
    "recursive": (("cabinet",), ("drawer_chest",), ("cabinet", "drawer_chest")),
    "occlusion": (("cabinet",), ("nightstand",), ("cabinet", "drawer_chest")),
}
_MARGIN = 0.015  # free space between a thing and the inside of the box put over it
_GAP = 0.02  # between neighbouring things, and kept to the table's edge
_TRIES = 60


class _Draw:
    """One attempt at a variant; every choice comes from the task's generator."""

    def __init__(self, rng: np.random.Generator, task: str, seed: int) -> None:
        self.rng, self.task, self.seed = rng, task, seed
        self.size = (round(float(rng.uniform(1.3, 1.7)), 2), round(float(rng.uniform(0.8, 0.95)), 2))
        self.colour = str(rng.choice(("white", "brown", "grey")))
        self.pieces: list[tuple[str, StoragePlacement]] = []
        self.objects: list[TabletopObject] = []
        self.clear: list[Rect] = []  # storage footprints and the reach of every part
        self.used: dict[tuple[int, str], list[Rect]] = {}  # what stands in each slot, slot-local
        self.next_id = TABLE_ID + 1

    def scene(self) -> TabletopScene | None:
        names = _TASK_STORAGE[self.task][int(self.rng.integers(len(_TASK_STORAGE[self.task])))]
        if not self.place_storage(names):
            return None
        if self.task == "recursive" and not self.nest(in_storage=bool(self.rng.random() < 0.6)):
            return None
        hidden = int(self.rng.integers(1, 4))
        if self.task == "drawer-door":  # something behind a door and something in a drawer
            if not (self.hide(hidden, "door") and self.hide(1, "drawer")):
                return None
        elif not self.hide(hidden, None):
            return None
        if self.task == "occlusion" and not all(self.obstacle() for _ in range(1 + int(self.rng.random() < 0.3))):
            return None
        for _ in range(int(self.rng.integers(1, 4))):
            if self.on_table(self.item(), self.rng.random() < 0.3) is None:
                return None
        return self.finish()

    def uniform(self, lo: Sequence[float], hi: Sequence[float]) -> tuple[float, float, float]:
        """A size drawn between two corners, to the centimetre."""
        return tuple(round(float(self.rng.uniform(a, b)), 2) for a, b in zip(lo, hi))  # type: ignore[return-value]

    def item(self) -> str:
        return str(self.rng.choice(_ITEMS))

    def new_id(self) -> int:
        self.next_id += 1
        return self.next_id - 1

    def place_storage(self, names: Sequence[str]) -> bool:
        models = [storage_model(n, self.rng, self.uniform(*_STORAGE[n])) for n in names]
        length, depth = self.size
        spare = length - sum(m.size[0] for m in models) - _GAP * (len(models) + 1)
        if spare < 0:
            return False
        gaps = self.rng.dirichlet(np.ones(len(models) + 1)) * spare
        x = -length / 2 + _GAP
        for model, gap in zip(models, gaps):
            x += float(gap)
            back = depth / 2 - _GAP  # against the back edge, facing the robot
            pose = (round(x + model.size[0] / 2, 3), round(back - model.size[1] / 2, 3), TABLE_HEIGHT, 0.0)
            placement = StoragePlacement(self.new_id(), model, pose, 0)
            colour = str(self.rng.choice([c for c in _PAINTS if c != self.colour]))
            self.pieces.append((colour, placement))
            self.clear.append(placement.footprint())
            for part in model.parts:
                points = placement.to_world(sweep_points(model, part))
                lo, hi = points.min(axis=0), points.max(axis=0)
                self.clear.append((lo[0] - _GAP, lo[1] - _GAP, hi[0] + _GAP, hi[1] + _GAP))
            x += model.size[0] + _GAP
        return True

    def in_slot(self, category: str, shape: str, dims: tuple[float, ...], kind: str | None) -> TabletopObject | None:
        """``category`` standing in a random slot (behind a part of ``kind`` if given) that fits it."""
        half = half_extents(shape, dims)
        slots = [(placement, slot) for _, placement in self.pieces for slot in placement.model.slots
                 if kind in (None, placement.model.part(slot.access).kind) and np.all(2 * half <= slot.size)]
        if not slots:
            return None
        placement, slot = slots[int(self.rng.integers(len(slots)))]
        room = np.asarray(slot.size[:2]) / 2 - half[:2]
        for _ in range(_TRIES):
            dx, dy = (float(self.rng.uniform(-r, r)) for r in room)
            rect = (dx - half[0], dy - half[1], dx + half[0], dy + half[1])
            taken = self.used.setdefault((placement.furniture_id, slot.name), [])
            if all(not rects_overlap(_grow(rect), other) for other in taken):
                taken.append(rect)
                center = tuple(float(v) for v in placement.slot_spot(slot.name, float(half[2]), dx, dy))
                return self.add(category, shape, dims, center, "inside", placement.furniture_id, slot.name)
        return None

    def hide(self, count: int, kind: str | None) -> bool:
        return all(self.in_slot(c, *OBJECTS[c], kind) is not None for c in (self.item() for _ in range(count)))

    def on_table(self, category: str, on_top: bool, shape: str = "", dims: tuple[float, ...] = ()
                 ) -> TabletopObject | None:
        """``category`` on the table clear of every part's reach, or on top of a piece."""
        shape, dims = (shape, dims) if shape else OBJECTS[category]
        half = half_extents(shape, dims)
        parent, z = TABLE_ID, TABLE_HEIGHT
        area = (-self.size[0] / 2, -self.size[1] / 2, self.size[0] / 2, self.size[1] / 2)
        if on_top:
            _, placement = self.pieces[int(self.rng.integers(len(self.pieces)))]
            w, d, h = placement.model.size
            x, y, base, _ = placement.pose
            parent, z, area = placement.furniture_id, base + h, (x - w / 2, y - d / 2, x + w / 2, y + d / 2)
        lo, hi = np.add(area[:2], half[:2] + _GAP), np.subtract(area[2:], half[:2] + _GAP)
        if np.any(lo > hi):
            return None
        for _ in range(_TRIES):
            x, y = (round(float(self.rng.uniform(a, b)), 3) for a, b in zip(lo, hi))
            rect = (x - half[0], y - half[1], x + half[0], y + half[1])
            if self.free(rect, parent, check_clear=not on_top):
                return self.add(category, shape, dims, (x, y, round(z + float(half[2]), 4)), "on", parent)
        return None

    def free(self, rect: Rect, parent: int, check_clear: bool) -> bool:
        others = [o.footprint() for o in self.objects if o.relation == "on" and o.parent == parent]
        keep = [*others, *(self.clear if check_clear else [])]
        return all(not rects_overlap(_grow(rect), other) for other in keep)

    def nest(self, in_storage: bool) -> bool:
        """A chain of boxes over boxes over a thing: two levels of picks on the table, one or two in storage."""
        inner = self.item()
        levels = 2 if not in_storage else int(self.rng.integers(1, 3))
        chain = [(inner, *OBJECTS[inner])]
        for _ in range(levels):
            shape, dims = chain[-1][1], chain[-1][2]
            half = half_extents(shape, dims)
            outer = (*(round(float(2 * h + 2 * _MARGIN + 2 * SHELL_WALL), 3) for h in half[:2]),
                     round(float(2 * half[2] + _MARGIN + SHELL_WALL), 3))
            chain.append(("box", "shell", outer))
        category, shape, dims = chain[-1]
        if in_storage:
            outermost = self.in_slot(category, shape, dims, None)
        else:
            outermost = self.on_table(category, False, shape, dims)
        if outermost is None:
            return False
        parent, floor = outermost, outermost.center[2] - outermost.half_extents[2]
        for category, shape, dims in reversed(chain[:-1]):
            half = half_extents(shape, dims)
            center = (parent.center[0], parent.center[1], round(float(floor + half[2]), 4))
            parent = self.add(category, shape, dims, center, "inside", parent.instance_id)
        return True

    def obstacle(self) -> bool:
        """A tall thing standing where a closed door of some piece would swing through it."""
        doors = [(pl, part) for _, pl in self.pieces for part in pl.model.parts if part.kind == "door"]
        placement, part = doors[int(self.rng.integers(len(doors)))]
        category = str(self.rng.choice(_OBSTACLES))
        half = half_extents(*OBJECTS[category])
        front = placement.pose[1] - placement.model.size[1] / 2 - HANDLE_REACH - _GAP / 2
        points = placement.to_world(sweep_points(placement.model, part))
        points = points[(points[:, 1] < front - half[1]) & (points[:, 2] < TABLE_HEIGHT + 0.05)]
        length, depth = self.size
        for x, y, _ in points[self.rng.permutation(len(points))[:_TRIES]]:
            rect = (x - half[0], y - half[1], x + half[0], y + half[1])
            on_table = -length / 2 + _GAP <= rect[0] and rect[2] <= length / 2 - _GAP and -depth / 2 + _GAP <= rect[1]
            if on_table and self.free(rect, TABLE_ID, check_clear=False):
                center = (round(float(x), 3), round(float(y), 3), round(TABLE_HEIGHT + float(half[2]), 4))
                self.add(category, *OBJECTS[category], center, "on", TABLE_ID)
                return True
        return False

    def add(self, category: str, shape: str, dims: tuple[float, ...], center: tuple[float, float, float],
            relation: str, parent: int, slot: str | None = None) -> TabletopObject:
        colour = str(self.rng.choice(list(COLOURS)))
        obj = TabletopObject(self.new_id(), category, colour, shape, tuple(dims), center, relation, parent, slot)
        self.objects.append(obj)
        return obj

    def finish(self) -> TabletopScene:
        """Hand out part ids after every other thing and record what stands in which slot."""
        pieces = []
        for colour, placement in self.pieces:
            contents = tuple((o.instance_id, o.slot) for o in self.objects
                             if o.parent == placement.furniture_id and o.slot is not None)
            pieces.append((colour, replace(placement, first_part_id=self.next_id, contents=contents)))
            self.next_id += 2 * len(placement.model.parts)
        return TabletopScene(self.task, self.seed, self.size, self.colour, tuple(pieces), tuple(self.objects))


def _grow(rect: Rect) -> Rect:
    return (rect[0] - _GAP / 2, rect[1] - _GAP / 2, rect[2] + _GAP / 2, rect[3] + _GAP / 2)


def tabletop_variant(task: str, seed: int) -> TabletopScene:
    """Variant ``seed`` of ``task``; the same arguments always give the same scene.

    Args:
        task: the tabletop task (one of `TASKS`).
        seed: the variant.

    Returns:
        The scene.

    Raises:
        ValueError: an unknown task, or a negative seed.
    """
    if task not in TASKS:
        raise ValueError(f"task: {task!r} is not one of {TASKS}")
    if seed < 0:
        raise ValueError(f"seed: {seed} must be 0 or more")
    rng = np.random.default_rng([seed, TASKS.index(task)])
    for _ in range(_TRIES):
        scene = _Draw(rng, task, seed).scene()
        if scene is not None:
            return scene
    raise RuntimeError(f"{task} seed {seed}: no variant in {_TRIES} draws")


def build_tabletop(client: int, scene: TabletopScene) -> SegLabels:
    """Add ``scene`` to the (empty) simulation ``client``: table, articulated storage, static objects.

    Args:
        client: the PyBullet client.
        scene: the scene.

    Returns:
        The labels by body and link.
    """
    labels = scene.labels()
    length, depth = scene.table_size
    leg = TABLE_HEIGHT - 0.04
    boxes = [((0.0, 0.0, TABLE_HEIGHT - 0.02), (length, depth, 0.04))] + [
        ((sx * (length / 2 - 0.05), sy * (depth / 2 - 0.05), leg / 2), (0.05, 0.05, leg))
        for sx in (-1, 1) for sy in (-1, 1)
    ]
    seg: SegLabels = {(add_boxes(client, (0.0, 0.0, 0.0), boxes, COLOURS[scene.table_colour]), -1): labels[TABLE_ID]}
    for _, placement in scene.storage:
        seg.update(add_storage(client, placement, labels[placement.furniture_id])[1])
    for obj in scene.objects:
        rgba = COLOURS[obj.colour]
        if obj.shape == "shell":  # an open-bottom box: a lid and four walls
            (w, d, h), t = obj.dims, SHELL_WALL
            wall = h - t
            boards = [((0.0, 0.0, h / 2 - t / 2), (w, d, t))]
            boards += [((s * (w - t) / 2, 0.0, -t / 2), (t, d, wall)) for s in (-1, 1)]
            boards += [((0.0, s * (d - t) / 2, -t / 2), (w - 2 * t, t, wall)) for s in (-1, 1)]
            body = add_boxes(client, obj.center, boards, rgba)
        else:
            body = add_shape(client, obj.shape, obj.dims, obj.center, rgba)
        seg[(body, -1)] = labels[obj.instance_id]
    return seg


def write_tabletop_suites(out_dir: Path | str) -> list[Path]:
    """One JSON-lines file per task, ``<task>.jsonl``: per line ``{seed, task, scene, acsg}`` for the tuning seeds.

    Each file is written to a temporary name and renamed, so a reader never sees half a suite.

    Args:
        out_dir: the suites' directory.

    Returns:
        The files written.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for task in TASKS:
        lines = []
        for seed in SPLITS["tuning"].seeds():
            scene = tabletop_variant(task, seed)
            record = {"seed": seed, "task": task, "scene": scene.to_dict(), "acsg": scene.ground_truth_acsg()}
            lines.append(json.dumps(record))
        fd, tmp = tempfile.mkstemp(dir=out, suffix=".tmp")
        with os.fdopen(fd, "w") as handle:
            handle.write("\n".join(lines) + "\n")
        path = out / f"{task}.jsonl"
        os.replace(tmp, path)
        paths.append(path)
    return paths
