"""Parsing a message header's JSON within bounds a hostile sender cannot push past.

Python's own parser recurses once per level of nesting and converts integers of any length, so a
header of a thousand ``[`` or an integer of five thousand digits would end in ``RecursionError`` or
``ValueError`` deep inside it. Here the nesting is measured on the raw bytes before parsing, and
every integer is read by a hook that keeps those of the 64-bit range and marks the others, so the
message is refused naming the field that holds one (``path[0][1]``), before any handler sees it.
"""

from __future__ import annotations

import json
import re
from typing import Any

import numpy as np

#: The deepest nesting of objects and lists a header may have.
MAX_DEPTH = 64
#: Integers a header may hold: what a signed or unsigned 64-bit integer holds in any language.
INT_RANGE = (-(2**63), 2**64 - 1)
_MAX_DIGITS = len(str(INT_RANGE[1]))
_STRING = re.compile(rb'"[^"\\]*(?:\\.[^"\\]*)*"', re.DOTALL)
_OPEN, _CLOSE = np.frombuffer(b"[{", np.uint8), np.frombuffer(b"]}", np.uint8)


class HeaderError(ValueError):
    """A header out of bounds; ``field`` is the path of the value at fault ("" for the whole header).

    Args:
        field: the value's path inside the header (``path[0][1]``), or "".
        problem: what is wrong with it.
    """

    def __init__(self, field: str, problem: str) -> None:
        super().__init__(f"{field}: {problem}" if field else problem)
        self.field = field
        self.problem = problem


class _Oversized:
    """An integer outside `INT_RANGE`, kept as its digits until its field is found."""

    def __init__(self, digits: str) -> None:
        self.digits = digits


def nesting_depth(raw: bytes) -> int:
    """How deeply objects and lists nest in the JSON text ``raw`` (strings' contents do not count).

    Args:
        raw: the JSON text.

    Returns:
        The depth: 0 for a scalar, 1 for a flat list or object.
    """
    structure = np.frombuffer(_STRING.sub(b"", raw), dtype=np.uint8)
    steps = np.isin(structure, _OPEN).astype(np.int64) - np.isin(structure, _CLOSE)
    return int(np.cumsum(steps).max(initial=0))


def parse_header_json(raw: bytes) -> Any:
    """The JSON value in ``raw``, refused when it nests deeper than `MAX_DEPTH` or holds an integer
    outside `INT_RANGE`.

    Args:
        raw: UTF-8 JSON text.

    Returns:
        The value.

    Raises:
        HeaderError: nested too deeply, or an integer out of range (naming its field).
        ValueError: not UTF-8 JSON (UnicodeDecodeError, json.JSONDecodeError).
    """
    if raw.count(b"[") + raw.count(b"{") > MAX_DEPTH:  # else too few brackets to nest that deeply
        depth = nesting_depth(raw)
        if depth > MAX_DEPTH:
            raise HeaderError("", f"nested deeper than {MAX_DEPTH} levels ({depth})")
    oversized: list[_Oversized] = []

    def integer(text: str) -> int | _Oversized:
        if len(text.lstrip("-")) <= _MAX_DIGITS:
            value = int(text)
            if INT_RANGE[0] <= value <= INT_RANGE[1]:
                return value
        oversized.append(_Oversized(text))
        return oversized[-1]

    try:
        value = json.loads(raw.decode("utf-8"), parse_int=integer)
    except RecursionError:  # the depth scan was misled by malformed text; still far too deep
        raise HeaderError("", f"nested deeper than {MAX_DEPTH} levels") from None
    if oversized:
        field, marker = _find(value, oversized[0])
        size = len(marker.digits.lstrip("-"))
        shown = marker.digits if size <= 24 else f"{marker.digits[:12]}…{marker.digits[-6:]}"
        raise HeaderError(field, f"the integer {shown} ({size} digits) is outside the 64-bit range "
                                 f"{INT_RANGE[0]}..{INT_RANGE[1]}")
    return value


def _find(value: Any, marker: _Oversized) -> tuple[str, _Oversized]:
    """The path of ``marker`` inside ``value``, without recursion."""
    stack: list[tuple[str, Any]] = [("", value)]
    while stack:
        path, item = stack.pop()
        if item is marker:
            return path, marker
        if isinstance(item, dict):
            stack.extend((f"{path}.{_key(key)}" if path else _key(key), child) for key, child in item.items())
        elif isinstance(item, list):
            stack.extend((f"{path}[{index}]", child) for index, child in enumerate(item))
    return "", marker  # not reached: the marker came from this value


def _key(key: str) -> str:
    return key if len(key) <= 40 else f"{key[:37]}..."
