"""Malformed world requests of many kinds, drawn from a seed, for `homebot bench fuzz` and its tests.

Each `Case` is what a hostile or broken client could send to one of the world's commands, written
from docs/bus.md alone: bytes that are not the wire format, headers nested too deeply or holding
integers of thousands of digits, malformed array tables, unknown fields and arrays, values of the
wrong type or beyond their bounds in every field of every command, scenarios that start in a
wall, scenes with walls at 1e308 or a room 99,999 m long. Every one must be refused with an error
naming the field. ``kind`` groups them in the report.
"""

from __future__ import annotations

import copy
import json
import math
import random
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from worlds.bus.codec import MAGIC, encode
from worlds.home import HomeSpec
from worlds.robot_arm import arm_spec

Meta = dict[str, Any]
_BIG = "@@big@@"  # stands for a raw JSON token (an integer json.dumps cannot write) until the bytes are made


@dataclass(frozen=True)
class Case:
    """One malformed request: its kind, the command it goes to, and its payload (None: no payload)."""

    kind: str
    verb: str
    payload: bytes


def _raw(header: bytes, payload: bytes = b"") -> bytes:
    return struct.pack(">4sI", MAGIC, len(header)) + header + payload


def _with_token(meta: Meta, token: str) -> bytes:
    """``meta`` as a message (NaN and infinities written as Python's JSON writes them) whose `_BIG`
    placeholder, if any, is replaced by the raw JSON ``token``."""
    header = json.dumps({**meta, "arrays": []}, separators=(",", ":")).replace(f'"{_BIG}"', token)
    return _raw(header.encode())


def _table(entries: list[Any], payload: bytes, meta: Meta | None = None) -> bytes:
    return _raw(json.dumps({**(meta or {}), "arrays": entries}).encode(), payload)


class Catalogue:
    """Draws cases from a seed, against a world reset to ``home`` with ``scenario``.

    Args:
        home: the home the world holds (a start pose inside one of its walls is drawn from it).
        scene: that home's scene spec (mutated into bad scenes).
        scenario: a scenario for it, as a dict (mutated into bad scenarios).
        seed: the draws' seed.
    """

    def __init__(self, home: HomeSpec, scene: Meta, scenario: Meta, seed: int = 0) -> None:
        self._rng = random.Random(seed)
        self._home, self._scene, self._scenario = home, scene, scenario
        self._stowed = np.array(arm_spec().stowed)
        self._makers: list[tuple[str, float, Callable[[], tuple[str, bytes]]]] = [
            ("not-the-format", 2.0, self._not_the_format),
            ("deep-nesting", 1.0, self._deep_nesting),
            ("huge-integer", 1.0, self._huge_integer),
            ("array-table", 2.0, self._array_table),
            ("unknown-array", 1.0, self._unknown_array),
            ("unknown-field", 1.0, self._unknown_field),
            ("wrong-value", 4.0, self._wrong_value),
            ("empty-payload", 0.5, self._empty_payload),
            ("bad-scenario", 1.0, self._bad_scenario),
            ("bad-scene", 0.5, self._bad_scene),
            ("bad-trajectory", 1.0, self._bad_trajectory),
        ]

    def cases(self, count: int) -> Iterator[Case]:
        """``count`` cases, kinds drawn by weight.

        Args:
            count: how many.

        Yields:
            The cases.
        """
        kinds = [name for name, _, _ in self._makers]
        weights = [weight for _, weight, _ in self._makers]
        makers = {name: make for name, _, make in self._makers}
        for _ in range(count):
            kind = self._rng.choices(kinds, weights)[0]
            verb, payload = makers[kind]()
            yield Case(kind, verb, payload)

    def _verb(self) -> str:
        return self._rng.choice(("reset", "observe", "move_base", "arm_state", "arm_trajectory", "gripper",
                                 "episode_report", "description"))

    def _not_the_format(self) -> tuple[str, bytes]:
        good = encode({"camera": "head"})
        bad = self._rng.choice([
            b"XXXX" + good[4:], good[: self._rng.randint(1, 7)], struct.pack(">4sI", MAGIC, 1000) + b"{}",
            struct.pack(">4sI", MAGIC, 2**31) + b"{}", _raw(b"\xff\xfe{}"), _raw(b"{not json"), _raw(b"[1, 2]"),
            _raw(b'"text"'), _raw(b"null"), _raw(b'{"a": 1,}'), _raw(b'{"camera": "' + b"x" * 200_000 + b'"}'),
        ])
        return self._verb(), bad

    def _deep_nesting(self) -> tuple[str, bytes]:
        depth = self._rng.choice([65, 100, 1_000, 10_000, 100_000])
        opener, closer = self._rng.choice([(b"[", b"]"), (b'{"a":', b"}")])
        return self._verb(), _raw(b'{"x":' + opener * depth + b"1" + closer * depth + b"}")

    def _huge_integer(self) -> tuple[str, bytes]:
        digits = "9" * self._rng.choice([21, 400, 4_301, 5_000, 100_000])
        verb, meta = self._rng.choice([
            ("reset", {"seed": _BIG}), ("reset", {"seed": 1, "n_rooms": _BIG}), ("move_base", {"path": [[_BIG, 1.0]]}),
            ("move_base", {"path": [[1.0, 1.0]], "yaw": _BIG}), ("arm_trajectory", {"dt": _BIG}),
            ("reset", {"seed": 0, "scenario": {**self._scenario, "budget": _BIG}}), ("observe", {"camera": _BIG}),
        ])
        return verb, _with_token(meta, self._rng.choice(["", "-"]) + digits)

    def _array_table(self) -> tuple[str, bytes]:
        entry = {"name": "samples", "dtype": "float64", "shape": [2, 8]}
        bad = self._rng.choice([
            _table(entry, b""), _table([{"name": "samples"}], b""), _table([["samples", "float64", [2]]], b""),
            _table([{**entry, "dtype": "object"}], b"\0" * 128), _table([{**entry, "dtype": 7}], b"\0" * 128),
            _table([{**entry, "shape": [-1, 8]}], b""), _table([{**entry, "shape": [1, 1, 1, 1, 1]}], b"\0" * 8),
            _table([{**entry, "shape": [2**40, 8]}], b""), _table([{**entry, "shape": [0, 2**62]}], b""),
            _table([entry, entry], b"\0" * 256), _table([{**entry, "name": ""}], b"\0" * 128),
            _table([{**entry, "name": f"a{i}", "shape": [1]} for i in range(17)], b"\0" * 136),
            _table([entry], b"\0" * 127), _table([entry], b"\0" * 129),
            _table([{"name": "flags", "dtype": "bool", "shape": [4]}], b"\x00\x01\x02\x01"),
        ])
        return self._verb(), bad

    def _unknown_array(self) -> tuple[str, bytes]:
        size = self._rng.choice([1, 1_000, 100_000, 1_000_000])
        verb = self._verb()
        meta = {"dt": 0.02} if verb == "arm_trajectory" else {"seed": 0} if verb == "reset" else {}
        arrays = {"junk": np.zeros(size, np.uint8)}
        if verb == "arm_trajectory":
            arrays["samples"] = self._stowed[None, :].repeat(2, axis=0)
        return verb, encode(meta, arrays)

    def _unknown_field(self) -> tuple[str, bytes]:
        verb = self._verb()
        return verb, encode({self._rng.choice(["colour", "speed", "", "x" * 1000, "arrays2"]): 1})

    def _wrong_value(self) -> tuple[str, bytes]:
        """One field of one command holds a value wrong for it: of another type, non-finite, out of bounds."""
        verb, meta, extra = self._rng.choice([
            ("reset", {"seed": _BIG}, [-1, 1.5, 2**63, 1e308]), ("reset", {"seed": 1, "n_rooms": _BIG}, [3, 11, 1.5]),
            ("reset", {"seed": 1, "tabletop": _BIG}, ["drawer"]), ("reset", {"seed": 1, "scene": _BIG}, [3]),
            ("reset", {"seed": 1, "scenario": _BIG}, [3]), ("observe", {"camera": _BIG}, ["eye", None]),
            ("move_base", {"path": _BIG}, [[[1, 2]] * 600, [[999.0, -999.0]] * 3]),
            ("move_base", {"path": [_BIG]}, [[1], [1, 2, 3]]),
            ("move_base", {"path": [[_BIG, 1.0]]}, [1e308, 2**63, -(2**63), 1001.0]),
            ("move_base", {"path": [[1.0, 1.0]], "yaw": _BIG}, [99.0, 1e308, 2**63]),
            ("arm_trajectory", {"dt": _BIG}, [0, -1, 2.0, 1e308, 2**63, 1e-320]),
            ("arm_trajectory", {"dt": 0.02, "stop_on_contact": _BIG}, [1, 0, "yes"]),
            ("arm_trajectory", {"dt": 0.02, "stop_on_new_contact": _BIG}, [1, 0, "yes"]),
            ("gripper", {"action": _BIG}, ["squeeze", None]),
        ])
        odd = self._rng.choice([*extra, "", "north", "x" * 10_000, [], {}, [1], {"a": {"b": {"c": 1}}}, _BIG])
        token = self._rng.choice(["NaN", "Infinity", "-Infinity", "1e999"]) if odd == _BIG else json.dumps(odd)
        return verb, _with_token(meta, token)

    def _empty_payload(self) -> tuple[str, bytes]:
        return self._rng.choice(["reset", "move_base", "gripper", "arm_trajectory"]), b""

    def _bad_scenario(self) -> tuple[str, bytes]:
        wall = self._rng.choice(self._home.walls)
        scenario = copy.deepcopy(self._scenario)
        name, value = self._rng.choice([
            ("start_pose", [1e6, -1e6, 99.0]), ("start_pose", [999.0, 0.0, 0.0]), ("start_pose", [*wall.center[:2], 0.0]),
            ("start_pose", [1.0, 1.0, 99.0]), ("start_pose", [1.0]), ("start_pose", [math.inf, 0.0, 0.0]),
            ("seed", -1), ("seed", 1.5), ("budget", 10**9), ("budget", 0), ("budget", -5), ("target", {"bogus": "x"}),
            ("target", {"room": 3}), ("target", []), ("answer", "E"), ("choices", ["a", "b", "c"]), ("question", 5),
            ("extra", 1),
        ])
        scenario[name] = value
        if self._rng.random() < 0.1:  # and another field left out
            del scenario[self._rng.choice(sorted(set(scenario) - {name}))]
        return "reset", _with_token({"seed": 0, "scenario": scenario}, "0")

    def _bad_scene(self) -> tuple[str, bytes]:
        scene = copy.deepcopy(self._scene)
        rng = self._rng
        wall, door = rng.choice(scene["walls"]), rng.choice(scene["doorways"])
        room, piece = rng.choice(scene["rooms"]), rng.choice([f for f in scene["furniture"] if f["storage"]])
        part = piece["storage"]["parts"][0]
        mutate = rng.choice([
            lambda: wall["center"].__setitem__(0, 1e308), lambda: wall["size"].__setitem__(0, 2e9),
            lambda: door.__setitem__("width", 1e308), lambda: room["rect"].__setitem__(2, 99999.0),
            lambda: room["rect"].__setitem__(2, 999.0), lambda: wall["center"].__setitem__(0, 900.0),
            lambda: part.__setitem__("name", 'x"/><link name="y'), lambda: part.__setitem__("handle", part["name"]),
            lambda: part.__setitem__("handle", "carcass"), lambda: piece["storage"].__setitem__("panels", []),
            lambda: piece["storage"].__setitem__("parts", [part] * 100), lambda: piece.__setitem__("id", 2**40),
            lambda: piece.__setitem__("facing", 0.3), lambda: part.__setitem__("state", 1e9),
            lambda: scene.__setitem__("walls", [wall] * 1100), lambda: scene.__setitem__("seed", -1),
            lambda: scene.__setitem__("version", 99), lambda: scene["objects"][0].__setitem__("center", [math.nan] * 3),
            lambda: scene["objects"][0].__setitem__("attributes", {"x": 1e300}), lambda: room.__setitem__("name", "x" * 500),
        ])
        mutate()
        return "reset", _with_token({"seed": 0, "scene": _BIG}, json.dumps(scene, separators=(",", ":")))

    def _bad_trajectory(self) -> tuple[str, bytes]:
        stowed = self._stowed
        samples = stowed[None, :].repeat(4, axis=0)
        fast, out, nan = samples.copy(), samples.copy(), samples.copy()
        fast[2, 0] += 0.5
        out[1, 2] = 9.0
        nan[3, 4] = np.nan
        meta, bad = self._rng.choice([
            ({"dt": 0.02}, samples.astype(np.int32)), ({"dt": 0.02}, samples[:, :7]), ({"dt": 0.02}, samples[0]),
            ({"dt": 0.02}, samples[:0]), ({"dt": 0.001}, stowed[None, :].repeat(20_001, axis=0)),
            ({"dt": 0.02}, fast), ({"dt": 0.02}, out), ({"dt": 0.02}, nan), ({"dt": 0.0}, samples),
            ({"dt": 2.0}, samples), ({"dt": 1.0}, stowed[None, :].repeat(200, axis=0)),
            ({"dt": 0.02}, samples.astype(bool)), ({"dt": 0.02}, samples + 1.0),
        ])
        return "arm_trajectory", self._trajectory(meta, bad)

    @staticmethod
    def _trajectory(meta: Meta, samples: np.ndarray) -> bytes:
        return encode(meta, {"samples": samples})
