"""The run folder: result JSON, the snapshot log (JSON lines) and a picture of the final map."""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any


def write_json_atomic(path: Path, data: Any, indent: int | None = 2) -> None:
    """Write through a temporary file and rename, so a reader never sees half a file.

    ``indent=None`` writes compact JSON, for large files people do not read by eye.

    Args:
        path: the file.
        data: what to write (JSON-able).
        indent: the indent, or None for compact JSON.
    """
    temporary = path.with_suffix(path.suffix + ".tmp")
    separators = None if indent is not None else (",", ":")
    temporary.write_text(json.dumps(data, indent=indent, separators=separators, ensure_ascii=False) + "\n")
    os.replace(temporary, path)


class SnapshotLog:
    """Appends each snapshot as one JSON line, flushed, so an interrupted run keeps what it logged.

    Args:
        path: the JSON-lines file, appended to.
    """

    def __init__(self, path: Path) -> None:
        self._file = open(path, "a", encoding="utf-8")

    def __call__(self, data: dict[str, Any]) -> None:
        self._file.write(json.dumps(data, ensure_ascii=False, separators=(",", ":")) + "\n")
        self._file.flush()

    def close(self) -> None:
        self._file.close()
