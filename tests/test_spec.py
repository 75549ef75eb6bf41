"""The scene spec: round trips exactly, and a malformed spec is refused with the field named."""

from __future__ import annotations

import copy
import json
import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from worlds.home import HomeSpec, generate_home
from worlds.spec import FORMAT, VERSION, SpecError, dump_spec, load_spec, read_spec_file


@pytest.fixture(scope="module")
def home() -> HomeSpec:
    return generate_home(5, 8, 200.0)


@pytest.fixture
def spec(home: HomeSpec) -> dict[str, Any]:
    return dump_spec(home)


def _index(spec: dict[str, Any], section: str, match: Callable[[dict[str, Any]], bool]) -> int:
    return next(i for i, entry in enumerate(spec[section]) if match(entry))


@pytest.mark.parametrize("seed, n_rooms, area", [(0, None, None), (1, 4, 60.0), (2, 10, 300.0), (3, 6, 120.0)])
def test_round_trip_through_json_text(seed: int, n_rooms: int | None, area: float | None) -> None:
    home = generate_home(seed, n_rooms, area)
    text = json.dumps(dump_spec(home))
    again = load_spec(json.loads(text))
    assert again == home
    assert json.dumps(dump_spec(again)) == text
    assert HomeSpec.from_dict(json.loads(text)) == home and home.to_dict() == json.loads(text)


def test_spec_header_and_sections(spec: dict[str, Any], home: HomeSpec) -> None:
    assert (spec["format"], spec["version"], spec["seed"]) == (FORMAT, VERSION, home.seed)
    assert len(spec["rooms"]) == len(home.rooms) and len(spec["objects"]) == len(home.objects)
    storage = next(f for f in spec["furniture"] if f["storage"] is not None)
    assert {"model", "size", "parts", "slots", "panels"} == set(storage["storage"])
    assert all("state" in part and part["lower"] <= part["state"] <= part["upper"] for part in storage["storage"]["parts"])
    assert {r["type"] for r in spec["rooms"]} >= {"kitchen", "bedroom"}


def _upper_joint(spec: dict[str, Any]) -> str:
    f = _index(spec, "furniture", lambda e: e["storage"] is not None and len(e["storage"]["parts"]) > 1)
    spec["furniture"][f]["storage"]["parts"][1]["state"] = 9.5
    return rf"furniture\[{f}\]\.storage\.parts\[1\]\.state: 9\.5 is above the joint's upper limit"


def _missing_parent(spec: dict[str, Any]) -> str:
    i = _index(spec, "objects", lambda e: e["parent"] is not None)
    spec["objects"][i]["parent"] = 99999
    return rf"objects\[{i}\]\.parent: 99999 is not an instance id"


def _duplicate_id(spec: dict[str, Any]) -> str:
    spec["objects"][1]["id"] = spec["objects"][0]["id"]
    return r"objects\[1\]\.id: \d+ is already the id of objects\[0\]"


def _overlapping_rooms(spec: dict[str, Any]) -> str:
    spec["rooms"][2]["rect"] = list(spec["rooms"][0]["rect"])
    return r"rooms\[2\]\.rect: overlaps rooms\[0\]"


def _object_outside(spec: dict[str, Any]) -> str:
    i = _index(spec, "objects", lambda e: e["relation"] == "floor")
    spec["objects"][i]["center"][0] += 500.0
    return rf"objects\[{i}\]\.center: .* is outside its room"


def _wrong_slot(spec: dict[str, Any]) -> str:
    i = _index(spec, "objects", lambda e: e["slot"] is not None)
    spec["objects"][i]["slot"] = "attic"
    return rf"objects\[{i}\]\.slot: 'attic' is not a slot of"


def _inside_a_plate(spec: dict[str, Any]) -> str:
    i = _index(spec, "objects", lambda e: e["relation"] == "inside" and e["slot"] is None)
    parent = _index(spec, "objects", lambda e: e["id"] == spec["objects"][i]["parent"])
    spec["objects"][parent]["category"] = "plate"
    return rf"objects\[{i}\]\.parent: \d+ is a plate, which holds nothing inside"


def _bad_facing(spec: dict[str, Any]) -> str:
    spec["furniture"][0]["facing"] = 0.3
    return r"furniture\[0\]\.facing: 0\.3 is not a multiple of pi/2"


def _cabinet_without_storage(spec: dict[str, Any]) -> str:
    f = _index(spec, "furniture", lambda e: e["storage"] is not None)
    spec["furniture"][f]["storage"] = None
    return rf"furniture\[{f}\]\.storage: a \w[\w ]* needs a storage model"


def _set(path: list[Any], value: Any, pattern: str) -> Callable[[dict[str, Any]], str]:
    def mutate(spec: dict[str, Any]) -> str:
        target = spec
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
        return pattern
    return mutate


def _drop(path: list[Any], pattern: str) -> Callable[[dict[str, Any]], str]:
    def mutate(spec: dict[str, Any]) -> str:
        target = spec
        for key in path[:-1]:
            target = target[key]
        del target[path[-1]]
        return pattern
    return mutate


MALFORMED: dict[str, Callable[[dict[str, Any]], str]] = {
    "old version": _set(["version"], 1, r"^version: 1 is not supported \(expected 2\)$"),
    "other format": _set(["format"], "blender", r"^format: 'blender' is not 'homebot-scene'$"),
    "unknown top key": _set(["colour_scheme"], "warm", r"^colour_scheme: unknown key$"),
    "unknown nested key": _set(["walls", 0, "texture"], "brick", r"^walls\[0\]\.texture: unknown key$"),
    "missing key": _drop(["rooms", 0, "rect"], r"^rooms\[0\]\.rect: missing$"),
    "wrong type": _set(["walls", 3, "size"], "big", r"^walls\[3\]\.size: expected a list, got str$"),
    "boolean seed": _set(["seed"], True, r"^seed: expected an integer, got True$"),
    "not finite": _set(["furniture", 0, "center", 1], math.nan, r"^furniture\[0\]\.center\[1\]: nan is not a finite number$"),
    "negative size": _set(["walls", 0, "size", 2], -2.5, r"^walls\[0\]\.size\[2\]: -2\.5 must be positive$"),
    "unknown word": _set(["objects", 0, "category"], "unicorn", r"^objects\[0\]\.category: 'unicorn' is not one of"),
    "unknown state": _set(["furniture", 0, "state"], {"power": "half"}, r"^furniture\[0\]\.state\.power: 'half' is not one of"),
    "room name of another type": _set(["rooms", 0, "name"], "garage", r"^rooms\[0\]\.name: 'garage' is not a name for"),
    "joint beyond its limit": _upper_joint,
    "parent that does not exist": _missing_parent,
    "duplicate id": _duplicate_id,
    "overlapping rooms": _overlapping_rooms,
    "object outside its room": _object_outside,
    "slot the parent lacks": _wrong_slot,
    "parent that holds nothing": _inside_a_plate,
    "facing askew": _bad_facing,
    "storage missing": _cabinet_without_storage,
}


@pytest.mark.parametrize("name", MALFORMED)
def test_malformed_spec_is_refused_with_the_field_named(spec: dict[str, Any], name: str) -> None:
    broken = copy.deepcopy(spec)
    pattern = MALFORMED[name](broken)
    with pytest.raises(SpecError) as caught:
        load_spec(broken)
    assert any(re.search(pattern, line) for line in caught.value.errors), caught.value.errors


def test_every_problem_is_reported_at_once(spec: dict[str, Any]) -> None:
    broken = copy.deepcopy(spec)
    broken["walls"][0]["size"][0] = "thick"
    broken["objects"][2]["colour"] = "plaid"
    with pytest.raises(SpecError) as caught:
        load_spec(broken)
    assert len(caught.value.errors) == 2 and str(caught.value).count("\n") == 1
    assert caught.value.errors[0].startswith("walls[0].size[0]") and caught.value.errors[1].startswith("objects[2].colour")


def test_not_an_object_at_all() -> None:
    with pytest.raises(SpecError, match="expected an object, got list"):
        load_spec([1, 2, 3])


def test_read_spec_file_names_the_file(tmp_path: Path, spec: dict[str, Any], home: HomeSpec) -> None:
    good = tmp_path / "home.json"
    good.write_text(json.dumps(spec))
    assert read_spec_file(good) == home
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "homebot-scene", "version": 2,')
    with pytest.raises(SpecError, match=r"bad\.json: not valid JSON \(.*line 1"):
        read_spec_file(bad)
    with pytest.raises(SpecError, match=r"nowhere\.json: cannot read"):
        read_spec_file(tmp_path / "nowhere.json")
