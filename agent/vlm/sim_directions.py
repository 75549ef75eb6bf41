"""How promising the simulated VLM finds a view, or the region around a letter drawn on it, for
exploring towards an answer: the value behind LSV and GSV (Explore until Confident, §IV-C).

The value is read from what the region shows and from common sense (`agent.vlm.commonsense`):
the thing asked about itself is worth 1; a floor the model takes for the room the question names
is worth `commonsense.NAMED_ROOM_VALUE`, one of a room of unknown kind `commonsense.UNKNOWN_ROOM`
(it might be that room), one of another kind `commonsense.UNLISTED`; with no room named, a room's
value is how likely the thing is kept in a room of its kind; a view through to another floor than
the one the robot stands on is worth at least `commonsense.DOORWAY_VALUE`. For a question about
what is in a piece of storage the piece is the thing to go to, and what stands in view says which
room it is (`commonsense.room_cue`).
"""

from __future__ import annotations

import numpy as np

from agent.observation import InstanceLabel
from agent.vlm import commonsense
from agent.vlm.sim_frame import FrameTake
from worlds.questions import ParsedQuestion
from worlds.vocabulary import room_kind

#: Pixels an instance must fill in a region for the direction values to count it as seen there.
SEEN_PX = 20


def view_value(take: FrameTake, question: ParsedQuestion | None, mark: tuple[float, float] | None,
               window: float) -> float:
    """The value in [0, 1] of the whole view (``mark`` None) or of the square of half-size
    ``window`` (a share of the image width) around the pixel ``mark``.

    Args:
        take: what the model makes of the frame.
        question: the question, or None when it was not understood.
        mark: the pixel (u, v), or None for the whole view.
        window: the square's half-size.

    Returns:
        The value.
    """
    seg = take.observation.segmentation
    if mark is not None:
        half = max(1, int(window * seg.shape[1]))
        u, v = int(mark[0]), int(mark[1])
        seg = seg[max(0, v - half): v + half, max(0, u - half): u + half]
    ids, counts = np.unique(seg[seg >= 0], return_counts=True)
    if ids.size == 0:
        return 0.0
    labels = {seen.label.id: seen.label for seen in take.seen}
    in_view = [(labels[i], n) for i, n in zip(ids.tolist(), counts.tolist()) if i in labels]
    floors = [label.id for label, _ in in_view if label.id in take.rooms.floors]
    seen = [label for label, n in in_view if label.category != "floor" and n >= SEEN_PX]
    storage = question is not None and question.template.hidden
    target = None if storage or question is None else (question.category or question.appliance or question.container)
    value = 1.0 if target is not None and any(label.category == target for label in seen) else 0.0
    if storage:
        value = max(value, _storage_value(take, seen, question))
    if floors:
        value = max(value, _room_value(take, floors, question, target))
        here = take.floor_at_feet()
        if any(floor != here for floor in floors):
            value = max(value, commonsense.DOORWAY_VALUE + 0.5 * value)
    return float(min(1.0, value))


def _room_value(take: FrameTake, floors: list[int], question: ParsedQuestion | None, target: str | None) -> float:
    """The best value of the rooms whose floors show: the named room wins whatever usually lives
    where; with none named, where the thing usually lives."""
    kinds = {take.region_kind(floor) for floor in floors}
    named = None if question is None or question.room is None else room_kind(question.room)
    if named is not None:
        if named in kinds:
            return commonsense.NAMED_ROOM_VALUE
        return commonsense.UNKNOWN_ROOM if None in kinds else commonsense.UNLISTED
    return max(commonsense.UNKNOWN_ROOM if kind is None else commonsense.affinity(target, kind) for kind in kinds)


def _storage_value(take: FrameTake, seen: list[InstanceLabel], question: ParsedQuestion) -> float:
    """1 when a piece of the storage kind asked about is in view, unless the model takes it to
    stand in another room than the named one; else how strongly what stands in view suggests the
    named room (a toilet a bathroom), scaled to `commonsense.NAMED_ROOM_VALUE`."""
    named = None if question.room is None else room_kind(question.room)
    for label in seen:
        if label.category == question.container and (
                named is None or take.room_of(label.id, ignoring=(label.id,)) in (None, named)):
            return 1.0
    if question.room is None:
        return 0.0
    cues = [label.category for label in seen if label.category != question.container]
    return commonsense.NAMED_ROOM_VALUE * commonsense.room_cue(cues, question.room)
