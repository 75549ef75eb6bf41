"""Checking JSON values field by field, collecting every problem with the path of its field.

The scene spec reader (worlds.spec) asks a `FieldChecker` for each field it needs; a value that is
missing, of the wrong type, non-finite, out of range or not one of the allowed words is recorded
as ``"furniture[3].size[1]: -0.2 must be positive"`` and comes back as None, so the reader skips
what it cannot build and goes on to find the next problem. One pass reports every problem. Every
number has bounds (an integer of any length is compared with them, never converted), every word
a length, and a name (of a part, a handle, a slot) only the characters of an identifier.
"""

from __future__ import annotations

import math
import re
from collections.abc import Collection
from typing import Any

#: The longest word or name a spec may hold.
MAX_WORD = 64
_NAME = re.compile(r"^[A-Za-z0-9_\-]+(/[A-Za-z0-9_\-]+)*$")


class SpecError(ValueError):
    """A scene spec that cannot be used. ``errors`` holds one 'path: problem' line per problem.

    Args:
        errors: the problems.
    """

    def __init__(self, errors: list[str]) -> None:
        super().__init__("\n".join(errors))
        self.errors = errors


def shown(value: Any) -> str:
    """``value`` as an error message shows it: at most about 40 characters, whatever its size.

    Args:
        value: any JSON value.

    Returns:
        The text.
    """
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**20:
        return f"an integer of {value.bit_length()} bits"
    text = repr(value) if not isinstance(value, (str, list, dict)) or len(value) <= 40 else repr(value[:40])
    return text if len(text) <= 40 else text[:37] + "..."


class FieldChecker:
    """Reads fields and records problems; each method returns the checked value or None."""

    def __init__(self) -> None:
        self.errors: list[str] = []

    def fail(self, path: str, problem: str) -> None:
        """Record a problem at the field ``path``.

        Args:
            path: the field's dotted path.
            problem: what is wrong.
        """
        self.errors.append(f"{path}: {problem}")

    def record(self, value: Any, path: str, required: Collection[str], optional: Collection[str] = ()) -> dict | None:
        """A JSON object with exactly the ``required`` keys and perhaps some ``optional`` ones.

        Args:
            value: the value read.
            path: its dotted path.
            required: the keys it must have.
            optional: the keys it may have.

        Returns:
            The object, or None (with the problems recorded).
        """
        if not isinstance(value, dict):
            self.fail(path or "spec", f"expected an object, got {type(value).__name__}")
            return None
        ok = True
        for key in value:
            if key not in required and key not in optional:
                self.fail(f"{path}.{key}" if path else str(key), "unknown key")
                ok = False
        for key in required:
            if key not in value:
                self.fail(f"{path}.{key}" if path else key, "missing")
                ok = False
        return value if ok else None

    def array(self, value: Any, path: str) -> list | None:
        """A JSON list.

        Args:
            value: the value read.
            path: its dotted path.

        Returns:
            The list, or None (with the problem recorded).
        """
        if not isinstance(value, list):
            self.fail(path, f"expected a list, got {type(value).__name__}")
            return None
        return value

    def number(self, value: Any, path: str, most: float, positive: bool = False) -> float | None:
        """A finite number (not a boolean) within ±``most``, positive when asked.

        Args:
            value: the value read.
            path: its dotted path.
            most: the largest magnitude allowed.
            positive: whether it must be above zero.

        Returns:
            The number, or None (with the problem recorded).
        """
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.fail(path, f"expected a number, got {shown(value)}")
            return None
        if isinstance(value, float) and not math.isfinite(value):
            self.fail(path, f"{value} is not a finite number")
            return None
        if not -most <= value <= most:
            self.fail(path, f"{shown(value)} is beyond ±{most:g}")
            return None
        if positive and value <= 0:
            self.fail(path, f"{value} must be positive")
            return None
        return float(value)

    def integer(self, value: Any, path: str, least: int, most: int) -> int | None:
        """An integer (not a boolean) in ``least``..``most``.

        Args:
            value: the value read.
            path: its dotted path.
            least: the smallest allowed.
            most: the largest allowed.

        Returns:
            The integer, or None (with the problem recorded).
        """
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(path, f"expected an integer, got {shown(value)}")
            return None
        if value < least:
            self.fail(path, f"{value} must be at least {least}")
            return None
        if value > most:
            self.fail(path, f"{shown(value)} must be at most {most}")
            return None
        return value

    def word(self, value: Any, path: str, choices: Collection[str] | None = None) -> str | None:
        """A non-empty string, one of ``choices`` when given.

        Args:
            value: the value read.
            path: its dotted path.
            choices: the words allowed (any when None).

        Returns:
            The word, or None (with the problem recorded).
        """
        if not isinstance(value, str) or not value:
            self.fail(path, f"expected a non-empty string, got {shown(value)}")
            return None
        if len(value) > MAX_WORD:
            self.fail(path, f"{shown(value)} is longer than {MAX_WORD} characters")
            return None
        if choices is not None and value not in choices:
            listed = ", ".join(sorted(choices)) if len(choices) <= 12 else f"{len(choices)} known words"
            self.fail(path, f"{value!r} is not one of {listed}")
            return None
        return value

    def name(self, value: Any, path: str) -> str | None:
        """A word made of letters, digits, ``_`` and ``-``, perhaps in chunks joined by ``/`` (what a
        part, a handle or a slot is called: the simulator's model of the piece carries these names).

        Args:
            value: the value read.
            path: its dotted path.

        Returns:
            The name, or None (with the problem recorded).
        """
        word = self.word(value, path)
        if word is not None and not _NAME.match(word):
            self.fail(path, f"{shown(word)} may hold only letters, digits, '_', '-' and '/' between them")
            return None
        return word

    def optional_word(self, value: Any, path: str, choices: Collection[str] | None = None) -> str | None:
        """A word or null; the caller tells a null apart from a bad value by the value itself.

        Args:
            value: the value read.
            path: its dotted path.
            choices: the words allowed (any when None).

        Returns:
            The word, or None.
        """
        return None if value is None else self.word(value, path, choices)

    def vector(self, value: Any, path: str, length: int, most: float,
               positive: bool = False) -> tuple[float, ...] | None:
        """A list of ``length`` finite numbers within ±``most``, positive when asked.

        Args:
            value: the value read.
            path: its dotted path.
            length: how many numbers.
            most: the largest magnitude allowed.
            positive: whether each must be above zero.

        Returns:
            The numbers, or None (with the problems recorded).
        """
        items = self.array(value, path)
        if items is None:
            return None
        if len(items) != length:
            self.fail(path, f"expected {length} numbers, got {len(items)}")
            return None
        numbers = [self.number(v, f"{path}[{i}]", most, positive) for i, v in enumerate(items)]
        return None if any(n is None for n in numbers) else tuple(numbers)  # type: ignore[arg-type]

    def words(self, value: Any, path: str, allowed: dict[str, Collection[str]] | None = None) -> dict[str, str] | None:
        """A JSON object of string values; with ``allowed``, only those keys and values.

        Args:
            value: the value read.
            path: its dotted path.
            allowed: the values allowed per key (any key and value when None).

        Returns:
            The object, or None (with the problems recorded).
        """
        if not isinstance(value, dict):
            self.fail(path, f"expected an object, got {type(value).__name__}")
            return None
        ok = True
        for key, item in value.items():
            if allowed is not None and key not in allowed:
                self.fail(f"{path}.{key}", "unknown key")
                ok = False
            elif self.word(item, f"{path}.{key}", None if allowed is None else allowed[key]) is None:
                ok = False
        return dict(value) if ok else None

    def scalars(self, value: Any, path: str, most: float) -> dict[str, Any] | None:
        """A JSON object of words, finite numbers within ±``most`` and booleans (free-form attributes).

        Args:
            value: the value read.
            path: its dotted path.
            most: the largest magnitude of a number.

        Returns:
            The object, or None (with the problems recorded).
        """
        if not isinstance(value, dict):
            self.fail(path, f"expected an object, got {type(value).__name__}")
            return None
        ok = True
        for key, item in value.items():
            if isinstance(item, bool) or (isinstance(item, str) and len(item) <= MAX_WORD):
                continue
            if isinstance(item, str):
                self.fail(f"{path}.{key}", f"{shown(item)} is longer than {MAX_WORD} characters")
                ok = False
            elif self.number(item, f"{path}.{key}", most) is None:
                ok = False
        return dict(value) if ok else None
