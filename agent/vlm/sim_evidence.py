"""What one frame tells the simulated VLM about one question: the choices it backs, and how sure.

The model answers from what it noticed (`agent.vlm.sim_frame.FrameTake`), the way a capable VLM
reads a picture: the colour of the mug in view, the number of cups it can count, the room the
furniture around a thing says it stands in. A question naming a room ("… in the kitchen?") is
taken at its word where the frame cannot tell: a thing in a part of the frame whose room nothing
names counts as being in that room. A thing the model takes to stand in another room counts only
when nothing fitting better is in view, and then only as a guess.

`Evidence.sure` says the frame settles the question (the model would say it is confident); a
guess (`sure` False with choices backed) is what it would say if pressed: the named room seen in
part without the thing ("No"), a thing whose room nothing in view tells (common sense says where
it is kept), a count of a room not in view.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from agent.observation import InstanceLabel
from agent.vlm import commonsense
from agent.vlm.sim_frame import FrameTake, Seen
from worlds.questions import ParsedQuestion
from worlds.vocabulary import COLOURS, OBJECTS, room_kind

_MISREAD_WORDS = {"colour": tuple(COLOURS), "category": tuple(OBJECTS)}
_PARTS = frozenset({"door", "drawer", "flap"})  # the parts of storage that open onto what it holds


@dataclass(frozen=True)
class Evidence:
    """``backed``: lower-cased choice texts the frame supports; ``sure``: whether it settles the
    question (else what it backs is a guess); ``inside``: it was read off a view into the open
    storage the question asks about."""

    backed: frozenset[str] = frozenset()
    sure: bool = False
    inside: bool = False


NONE = Evidence()


def evidence(take: FrameTake, question: ParsedQuestion, rng: np.random.Generator) -> Evidence:
    """What the frame says about the question (see the module docstring).

    Args:
        take: what the model makes of the frame.
        question: the parsed question.
        rng: the draws' generator.

    Returns:
        The evidence.
    """
    asks = question.template.asks
    if asks in ("power", "door"):
        return _state(take, question)
    if question.container is not None:
        return _in_storage(take, question, rng)
    if asks == "yes/no":
        return _exists(take, question)
    if asks == "count":
        return _count(take, question, rng)
    if asks == "room":
        return _room(take, question)
    return _attribute(take, question, rng)


def _named_kind(question: ParsedQuestion) -> str | None:
    return None if question.room is None else room_kind(question.room)


def _split_by_room(take: FrameTake, noticed: list[Seen], question: ParsedQuestion) -> tuple[list[Seen], list[Seen]]:
    """(things that may stand in the named room, things the model takes to stand in another). A
    thing may confirm its own room but not deny it: a counter says 'kitchen', while a tv, which
    says 'living room', may stand in a bedroom; so a thing fits when its region reads as the named
    room with it, or as that room or nothing without it."""
    named = _named_kind(question)
    fitting, elsewhere = [], []
    for seen in noticed:
        thing = seen.label.id
        fits = named is None or take.room_of(thing) == named or take.room_of(thing, ignoring=(thing,)) in (None, named)
        (fitting if fits else elsewhere).append(seen)
    return fitting, elsewhere


def _misread(value: str, words: tuple[str, ...], misread: float, rng: np.random.Generator) -> str:
    if rng.random() < misread:
        return str(rng.choice([word for word in words if word != value]))
    return value


def _fits(label: InstanceLabel, question: ParsedQuestion) -> bool:
    """A small object matching every attribute the question names except the one it asks."""
    asks = question.template.asks
    if label.category not in OBJECTS:
        return False
    return all(getattr(question, attribute) in (None, getattr(label, attribute))
               for attribute in ("category", "colour") if attribute != asks)


def _attribute(take: FrameTake, question: ParsedQuestion, rng: np.random.Generator) -> Evidence:
    """Colour of the {category} in the {room}; which object in the {room} is {colour}."""
    asks = question.template.asks
    fitting, elsewhere = _split_by_room(take, take.noticed(lambda label: _fits(label, question)), question)
    chosen = fitting or elsewhere
    backed = frozenset(_misread(getattr(seen.label, asks), _MISREAD_WORDS[asks], take.params.misread, rng)
                       for seen in chosen)
    return Evidence(backed, sure=bool(fitting))


def _room(take: FrameTake, question: ParsedQuestion) -> Evidence:
    """Which room is the {colour} {category} in: the room the furniture around it says; with
    nothing around it that tells, common sense (a mug: the kitchen) as a guess."""
    noticed = take.noticed(lambda label: _fits(label, question))
    rooms = {take.room_of(seen.label.id) for seen in noticed}
    told = frozenset(room for room in rooms if room is not None)
    if told:
        return Evidence(told, sure=True)
    if noticed:
        guess = max(commonsense.ROOM_AFFINITY.get(question.category or "", {}).items(),
                    key=lambda item: item[1], default=None)
        return Evidence(frozenset({guess[0]}) if guess else frozenset())
    return NONE


def _count(take: FrameTake, question: ParsedQuestion, rng: np.random.Generator) -> Evidence:
    """How many {plural} are there in the {room}: those noticed that may stand in it, when the
    room is in view or some are; misread by one with ``misread``."""
    fitting, _ = _split_by_room(take, take.noticed(lambda label: _fits(label, question)), question)
    room_seen = _room_in_view(take, question)
    if not fitting and not room_seen:
        return NONE
    count = len(fitting)
    if rng.random() < take.params.misread:
        count = max(0, count + int(rng.choice([-1, 1])))
    return Evidence(frozenset({str(count)}), sure=room_seen and bool(fitting))


def _exists(take: FrameTake, question: ParsedQuestion) -> Evidence:
    """Is there a {colour} {category} in the {room}: Yes on a match that may stand there; No when
    the room is in view without one."""
    fitting, _ = _split_by_room(take, take.noticed(lambda label: _fits(label, question)), question)
    if fitting:
        return Evidence(frozenset({"yes"}), sure=True)
    if _room_in_view(take, question):  # a room seen in part, without one: likely No, but not settled
        return Evidence(frozenset({"no"}))
    return NONE


def _in_storage(take: FrameTake, question: ParsedQuestion, rng: np.random.Generator) -> Evidence:
    """What is inside, or is there any {category} in, the {container} in the {room}: what the
    frame shows lying inside that kind of storage (the world says ``inside`` only where the
    storage's interior is in view); No, or nothing, when the storage stands open and empty: sure
    only when none of its doors and drawers in view is still shut."""
    open_pieces = _open_storage(take, question)
    is_open = bool(open_pieces)
    fitting, _ = _split_by_room(take, take.noticed(
        lambda label: label.inside == question.container and _fits(label, question)), question)
    if question.template.asks == "yes/no":
        if fitting:
            return Evidence(frozenset({"yes"}), sure=True, inside=is_open)
        if not is_open:
            return NONE
        # Open and empty settles it only when no door or drawer of the piece is still shut in view:
        # one empty drawer of a chest says little about the drawer below it.
        whole = not _shut_parts_on(take, open_pieces)
        return Evidence(frozenset({"no"}), sure=whole, inside=whole)
    backed = frozenset(_misread(seen.label.category, _MISREAD_WORDS["category"], take.params.misread, rng)
                       for seen in fitting)
    return Evidence(backed, sure=bool(backed), inside=bool(backed) and is_open)


def _state(take: FrameTake, question: ParsedQuestion) -> Evidence:
    """Is the {appliance} on or off; is the {container} open or closed: the visible state of the
    piece noticed."""
    wanted = question.appliance or question.container
    noticed = take.noticed(lambda label: label.category == wanted and label.state is not None)
    fitting, elsewhere = _split_by_room(take, noticed, question)
    return Evidence(frozenset(str(seen.label.state) for seen in fitting or elsewhere), sure=bool(fitting))


def _room_in_view(take: FrameTake, question: ParsedQuestion) -> bool:
    """Whether the parts of the frame taken for the named room fill ``room_view_fraction`` of it."""
    named = _named_kind(question)
    return named is not None and take.room_share(named) >= take.params.room_view_fraction


def _open_storage(take: FrameTake, question: ParsedQuestion) -> list[Seen]:
    """The pieces of the named storage kind the frame shows standing open, not taken to stand in
    another room than the named one."""
    pieces = [seen for seen in take.seen if seen.label.category == question.container and seen.label.state == "open"]
    fitting, _ = _split_by_room(take, pieces, question)
    return fitting


def _shut_parts_on(take: FrameTake, pieces: list[Seen]) -> bool:
    """Whether a door or drawer shown shut lies on one of ``pieces``: its pixels' centre within the
    piece's box in the image."""
    segmentation = take.observation.segmentation
    shut = [label.id for label in take.observation.labels if label.category in _PARTS and label.state == "closed"]
    if not shut:
        return False
    centres = []
    for part in shut:
        rows, cols = np.nonzero(segmentation == part)
        if rows.size:
            centres.append((rows.mean(), cols.mean()))
    for piece in pieces:
        rows, cols = np.nonzero(segmentation == piece.label.id)
        if rows.size and any(rows.min() <= r <= rows.max() and cols.min() <= c <= cols.max() for r, c in centres):
            return True
    return False
