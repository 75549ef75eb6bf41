"""Scenario suites: many seeded episodes written as JSON lines, split for calibration and test.

A suite line names everything needed to replay its episode: the seed (the home and the scenario
are both drawn from it), the scenario itself, and a checksum of the home's scene spec, so a suite
made by an older generator is caught rather than silently replayed in a different home. Writing
appends line by line and resumes: lines already in a file are kept and not made again.

Reading checks every line: a file with no scenario, a line that is not an entry and two entries
with one id are errors; only a torn last line after whole ones, what an interrupted append
leaves, is dropped. `checked_entries` and `suite_entry` check each home against its checksum too,
before any episode runs.
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from worlds.home import generate_home
from worlds.scenario import make_scenario

log = logging.getLogger(__name__)

SUITE_FORMAT = "homebot-suite"
SUITE_VERSION = 1
#: How many ids an unknown-id error lists.
_IDS_SHOWN = 4


class SuiteError(ValueError):
    """A suite file or request that cannot be used; the text names the line or field."""


@dataclass(frozen=True)
class SuitePart:
    """One output file of a suite: its name and the seeds it holds."""

    name: str
    seeds: range


def plan_split(n: int, split: list[int], seed_base: int, names: tuple[str, ...] = ("calib", "test")) -> list[SuitePart]:
    """Consecutive seed ranges for each part; ``split`` must add up to ``n``.

    Args:
        n: the entries in all.
        split: each part's size.
        seed_base: the first seed.
        names: the parts' names (more are made up when there are more parts).

    Returns:
        The parts.

    Raises:
        SuiteError: n not positive, or sizes that are not positive or do not add up to n.
    """
    if n <= 0:
        raise SuiteError(f"n: {n} must be positive")
    if sum(split) != n or any(k <= 0 for k in split):
        raise SuiteError(f"split: {'/'.join(map(str, split))} must be positive sizes adding up to n={n}")
    if len(split) > len(names):
        names = names + tuple(f"part{i}" for i in range(len(names), len(split)))
    parts, start = [], seed_base
    for name, size in zip(names, split):
        parts.append(SuitePart(name, range(start, start + size)))
        start += size
    return parts


def spec_checksum(spec: dict[str, Any]) -> str:
    """SHA-256 of the scene spec's canonical JSON.

    Args:
        spec: the scene spec.

    Returns:
        The hex digest.
    """
    return hashlib.sha256(json.dumps(spec, sort_keys=True, separators=(",", ":")).encode()).hexdigest()


def suite_line(seed: int, part: str, index: int, kinds: tuple[str, ...] | None = None,
               hidden: bool | None = None) -> dict[str, Any]:
    """The suite entry for ``seed``: the scenario and the checksum of its home.

    Args:
        seed: the home's and the scenario's seed.
        part: the suite part's name.
        index: the entry's index within the part.
        kinds: the question categories allowed (all when None).
        hidden: hidden-evidence questions only, never, or either (None).

    Returns:
        The entry.

    Raises:
        SuiteError: the home has no such question.
    """
    home = generate_home(seed)
    try:
        scenario = make_scenario(home, seed, kinds, hidden)
    except (ValueError, RuntimeError) as error:
        raise SuiteError(f"seed {seed}: {error}") from None
    return {
        "format": SUITE_FORMAT,
        "version": SUITE_VERSION,
        "id": f"{part}-{index:04d}",
        "seed": seed,
        "home_sha256": spec_checksum(home.to_dict()),
        "area_m2": round(home.area_m2, 2),
        "rooms": len(home.rooms),
        "scenario": scenario.to_dict(),
    }


def write_suite(out_dir: Path, parts: list[SuitePart],
                progress: Callable[[str, int, int], None] | None = None,
                kinds: tuple[str, ...] | None = None, hidden: bool | None = None) -> dict[str, Path]:
    """Write each part to ``<out_dir>/<name>.jsonl``, appending and resuming; return the paths.

    Args:
        out_dir: the suite's directory.
        parts: the parts to write.
        progress: called with (part, done, total) after each entry, if given.
        kinds: the question categories allowed (all when None).
        hidden: hidden-evidence questions only, never, or either (None).

    Returns:
        Each part's path by name.

    Raises:
        SuiteError: a seed's home has no such question.
    """
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = {}
    for part in parts:
        path = out_dir / f"{part.name}.jsonl"
        done = {entry["seed"] for entry in _kept_entries(path)} if path.exists() else set()
        with open(path, "a", encoding="utf-8") as out:
            for index, seed in enumerate(part.seeds):
                if seed not in done:
                    out.write(json.dumps(suite_line(seed, part.name, index, kinds, hidden), ensure_ascii=False) + "\n")
                    out.flush()
                if progress:
                    progress(part.name, index + 1, len(part.seeds))
        paths[part.name] = path
    return paths


def _kept_entries(path: Path) -> list[dict[str, Any]]:
    """The file's whole entries, rewriting it without a torn last line so appends start clean; an
    empty file, or one whose only line is torn, is a suite make interrupted early: nothing is kept."""
    entries, torn = _parse(path)
    if torn or len(entries) != len(path.read_text(encoding="utf-8").splitlines()):
        path.write_text("".join(json.dumps(e, ensure_ascii=False) + "\n" for e in entries), encoding="utf-8")
    return entries


def read_suite(path: Path) -> list[dict[str, Any]]:
    """Every entry of a suite file, checked. A torn last line (an interrupted ``suite make``: no
    line end, not JSON) after whole entries is dropped with a warning; anywhere else a line that is
    not an entry is an error. Blank lines are skipped.

    Args:
        path: the suite file.

    Returns:
        The entries, at least one.

    Raises:
        SuiteError: the file holds no entry (empty, or its only line torn), is not UTF-8, a line
            other than a torn last one is not a valid entry, or two entries share an id.
    """
    entries, torn = _parse(path)
    if not entries:
        raise SuiteError(f"{path}: holds no scenarios" + (
            ": its only line is not JSON (if an interrupted `homebot suite make` cut it short, run that "
            "again to finish the file)" if torn else " (make a suite with `homebot suite make`)"))
    if torn:
        log.warning("%s: dropping a torn last line (an interrupted write); %d scenarios kept", path, len(entries))
    return entries


def _parse(path: Path) -> tuple[list[dict[str, Any]], bool]:
    """The file's entries, and whether its last line was torn: not JSON and not ended by a line
    end, as an append cut short leaves it."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        line = error.object[:error.start].count(b"\n") + 1
        raise SuiteError(f"{path}:{line}: not UTF-8 text ({error.reason})") from None
    lines = text.splitlines()
    entries: list[dict[str, Any]] = []
    first_line_of: dict[str, int] = {}
    for number, line in enumerate(lines, start=1):
        if not line.strip():
            continue
        try:
            entry = json.loads(line)
        except (ValueError, RecursionError):  # not JSON, an integer of thousands of digits, deep nesting
            if number == len(lines) and not text.endswith("\n"):
                return entries, True
            raise SuiteError(f"{path}:{number}: not valid JSON") from None
        _check_entry(entry, f"{path}:{number}")
        if entry["id"] in first_line_of:
            raise SuiteError(f"{path}:{number}: scenario id {entry['id']!r} is already used on line "
                             f"{first_line_of[entry['id']]}; each scenario needs its own id")
        first_line_of[entry["id"]] = number
        entries.append(entry)
    return entries, False


def checked_entries(path: Path, limit: int | None = None) -> list[dict[str, Any]]:
    """The first ``limit`` entries of a suite file (all when None), each one's home checked: the
    home its seed generates must have the scene spec checksum the line records, else the episode
    would run in another home than the suite was made with.

    Args:
        path: the suite file.
        limit: how many entries, from the first.

    Returns:
        The entries.

    Raises:
        SuiteError: as `read_suite`, or an entry whose home does not match, naming its id.
    """
    entries = read_suite(path)[:limit]
    for entry in entries:
        check_home(entry, path)
    return entries


def check_home(entry: dict[str, Any], path: Path) -> None:
    """Refuse a suite entry whose seed does not generate the home its ``home_sha256`` records.

    Args:
        entry: an entry of `read_suite`.
        path: its suite file, for the message.

    Raises:
        SuiteError: naming the scenario's id.
    """
    try:
        checksum = spec_checksum(generate_home(entry["seed"]).to_dict())
    except ValueError as error:
        raise SuiteError(f"{path}: scenario {entry['id']}: {error}") from None
    if checksum != entry["home_sha256"]:
        raise SuiteError(f"{path}: scenario {entry['id']}: home_sha256 does not match the home seed {entry['seed']} "
                         "generates (the suite was made by another version of homebot, or edited); make it again "
                         "with `homebot suite make`")


def suite_entry(path: Path, entry_id: str) -> dict[str, Any]:
    """The entry of a suite file with id ``entry_id``, its home checked (`check_home`); a SuiteError
    naming how many entries the file holds, and the first few ids, when there is none.

    Args:
        path: the suite file.
        entry_id: the entry's id.

    Returns:
        The entry.

    Raises:
        SuiteError: as `read_suite`, no entry has that id, or its home does not match.
    """
    entries = read_suite(path)
    for entry in entries:
        if entry["id"] == entry_id:
            check_home(entry, path)
            return entry
    shown = ", ".join(entry["id"] for entry in entries[:_IDS_SHOWN]) + (", …" if len(entries) > _IDS_SHOWN else "")
    raise SuiteError(f"{path}: no scenario with id {entry_id!r}; the suite holds {len(entries)} scenarios"
                     + (f" ({shown})" if entries else ""))


def _check_entry(entry: Any, where: str) -> None:
    if not isinstance(entry, dict):
        raise SuiteError(f"{where}: expected a JSON object")
    if entry.get("format") != SUITE_FORMAT or entry.get("version") != SUITE_VERSION:
        raise SuiteError(f"{where}: format/version must be {SUITE_FORMAT!r}/{SUITE_VERSION}")
    for key, kind in (("id", str), ("seed", int), ("home_sha256", str), ("scenario", dict)):
        if not isinstance(entry.get(key), kind) or isinstance(entry.get(key), bool):
            raise SuiteError(f"{where}: {key} must be a {kind.__name__}")
