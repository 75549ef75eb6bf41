"""The wire codec: a small JSON header followed by raw array bytes.

A message on the bus is::

    b"HBW1" | uint32 big-endian header length | header (UTF-8 JSON object) | array bytes

The header is a JSON object with two reserved keys. ``"arrays"`` lists the arrays that follow, in
order, each as ``{"name": str, "dtype": str, "shape": [int, ...]}``; their bytes are packed back to
back in C order, little-endian. Every other key is free metadata for the message's kind.

Nothing here is ever unpickled or evaluated: the header is parsed as JSON within bounds (nesting,
integers: `worlds.bus.header_json`), checked field by field (dtype against an allow-list, shapes
against sizes, totals against limits) and only then are the array bytes viewed, so a malformed or
hostile message is rejected before it can cost memory. A ``bool`` element is one byte, 0 or 1.
"""

from __future__ import annotations

import json
import math
import struct
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from worlds.bus.header_json import HeaderError, parse_header_json

MAGIC = b"HBW1"
_PREFIX = struct.Struct(">4sI")

#: Array element types a message may carry; anything else is rejected.
ALLOWED_DTYPES: dict[str, np.dtype] = {
    name: np.dtype(name).newbyteorder("<")
    for name in ("uint8", "uint16", "int16", "int32", "int64", "float32", "float64", "bool")
}


class WireError(ValueError):
    """A message that does not follow the wire format; the text says which field and why.

    Args:
        message: the text, ``field: problem``.
        field: when one metadata value is at fault, its path in the header (``path[0][1]``), so a
            server can name it after its command (``move_base.path[0][1]``); else "".
        problem: with ``field``, what is wrong with that value.
    """

    def __init__(self, message: str, field: str = "", problem: str = "") -> None:
        super().__init__(message)
        self.field = field
        self.problem = problem


@dataclass(frozen=True)
class Limits:
    """Upper bounds a receiver enforces before it reads any array bytes."""

    max_header_bytes: int = 256 * 1024
    max_payload_bytes: int = 64 * 1024 * 1024
    max_arrays: int = 16
    max_ndim: int = 4


DEFAULT_LIMITS = Limits()


@dataclass
class Message:
    """A decoded message: JSON metadata and named arrays."""

    meta: dict[str, Any] = field(default_factory=dict)
    arrays: dict[str, np.ndarray] = field(default_factory=dict)


def encode(meta: dict[str, Any], arrays: dict[str, np.ndarray] | None = None) -> bytes:
    """Pack ``meta`` and ``arrays`` into one message. Raises WireError on unsupported arrays.

    Args:
        meta: the metadata (JSON-able; ``arrays`` is reserved).
        arrays: the arrays by name.

    Returns:
        The message's bytes.

    Raises:
        WireError: a reserved key or an unsupported array.
    """
    if "arrays" in meta:
        raise WireError("meta: the key 'arrays' is reserved for the array table")
    table = []
    chunks = []
    for name, array in (arrays or {}).items():
        dtype_name = np.dtype(array.dtype).name
        if dtype_name not in ALLOWED_DTYPES:
            raise WireError(f"arrays.{name}.dtype: {dtype_name!r} is not one of {sorted(ALLOWED_DTYPES)}")
        contiguous = np.asarray(array, dtype=ALLOWED_DTYPES[dtype_name], order="C")  # keeps 0-d arrays 0-d
        table.append({"name": name, "dtype": dtype_name, "shape": list(contiguous.shape)})
        chunks.append(contiguous.tobytes())
    header = json.dumps({**meta, "arrays": table}, separators=(",", ":"), allow_nan=False).encode()
    return b"".join([_PREFIX.pack(MAGIC, len(header)), header, *chunks])


def decode(data: bytes | bytearray | memoryview, limits: Limits = DEFAULT_LIMITS) -> Message:
    """Parse and validate a message. Raises WireError naming the first thing that is wrong.

    Args:
        data: the message's bytes.
        limits: the largest header, arrays and message accepted.

    Returns:
        The message.

    Raises:
        WireError: naming the first thing that is wrong.
    """
    view = memoryview(data)
    if len(view) < _PREFIX.size:
        raise WireError(f"message: truncated, {len(view)} bytes is shorter than the {_PREFIX.size}-byte prefix")
    magic, header_len = _PREFIX.unpack_from(view)
    if magic != MAGIC:
        raise WireError(f"message: bad magic {bytes(magic)!r}, expected {MAGIC!r}")
    if header_len > limits.max_header_bytes:
        raise WireError(f"header: {header_len} bytes exceeds the limit of {limits.max_header_bytes}")
    body = view[_PREFIX.size :]
    if len(body) < header_len:
        raise WireError(f"header: truncated, {len(body)} of {header_len} bytes present")
    header = _parse_header(bytes(body[:header_len]))
    specs = _check_array_table(header.pop("arrays", []), limits)
    payload = body[header_len:]
    expected = sum(nbytes for _, _, _, nbytes in specs)
    if expected > limits.max_payload_bytes:
        raise WireError(f"arrays: {expected} bytes exceeds the limit of {limits.max_payload_bytes}")
    if len(payload) != expected:
        raise WireError(f"arrays: the table describes {expected} bytes but {len(payload)} follow the header")
    arrays = {}
    offset = 0
    for name, dtype, shape, nbytes in specs:
        raw = np.frombuffer(payload[offset : offset + nbytes], dtype=dtype)
        if dtype.kind == "b" and raw.view(np.uint8).max(initial=0) > 1:
            raise WireError(f"arrays.{name}: a bool element is one byte, 0 or 1; found {raw.view(np.uint8).max()}")
        arrays[name] = raw.reshape(shape).astype(dtype.newbyteorder("="), copy=True)
        offset += nbytes
    return Message(meta=header, arrays=arrays)


def _parse_header(raw: bytes) -> dict[str, Any]:
    try:
        header = parse_header_json(raw)
    except HeaderError as error:
        where = f"header.{error.field}" if error.field else "header"
        in_table = error.field == "arrays" or error.field.startswith(("arrays[", "arrays."))  # not metadata
        field = "" if in_table else error.field
        raise WireError(f"{where}: {error.problem}", field, error.problem if field else "") from None
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise WireError(f"header: not valid UTF-8 JSON ({error})") from None
    if not isinstance(header, dict):
        raise WireError(f"header: must be a JSON object, got {type(header).__name__}")
    return header


def _check_array_table(table: Any, limits: Limits) -> list[tuple[str, np.dtype, tuple[int, ...], int]]:
    if not isinstance(table, list):
        raise WireError("header.arrays: must be a list")
    if len(table) > limits.max_arrays:
        raise WireError(f"header.arrays: {len(table)} arrays exceeds the limit of {limits.max_arrays}")
    specs = []
    seen: set[str] = set()
    for index, entry in enumerate(table):
        where = f"header.arrays[{index}]"
        if not isinstance(entry, dict) or set(entry) != {"name", "dtype", "shape"}:
            raise WireError(f"{where}: must be an object with exactly name, dtype and shape")
        name, dtype_name, shape = entry["name"], entry["dtype"], entry["shape"]
        if not isinstance(name, str) or not name or name in seen:
            raise WireError(f"{where}.name: must be a unique non-empty string")
        seen.add(name)
        if dtype_name not in ALLOWED_DTYPES:
            raise WireError(f"{where}.dtype: {dtype_name!r} is not one of {sorted(ALLOWED_DTYPES)}")
        if (
            not isinstance(shape, list)
            or len(shape) > limits.max_ndim
            or not all(isinstance(n, int) and not isinstance(n, bool) and n >= 0 for n in shape)
        ):
            raise WireError(f"{where}.shape: must be a list of at most {limits.max_ndim} non-negative integers")
        dtype = ALLOWED_DTYPES[dtype_name]
        nbytes = math.prod(shape) * dtype.itemsize
        if nbytes > limits.max_payload_bytes:
            raise WireError(f"{where}: {nbytes} bytes exceeds the limit of {limits.max_payload_bytes}")
        if math.prod(n for n in shape if n) > limits.max_payload_bytes:  # empty, but numpy cannot shape it
            raise WireError(f"{where}.shape: {shape} has more elements than the payload limit allows")
        specs.append((name, dtype, tuple(shape), nbytes))
    return specs
