"""One typed configuration with defaults, overridable from a TOML file and from the command line.

Every value is checked against the type of its default and, if a number or an address, against its
range in `agent.app.config_bounds`; a bad one is rejected with its full dotted name, e.g.
``config: map.resolution: expected a number, got 'fine'`` or ``config: map.resolution: 0.0 must
lie in (0, 10]``. Each section is the
settings class of the code it configures; ``act`` is the EQA tree's act branch (`LookInsideConfig`,
with ``act.approach`` its `ApproachConfig` and ``act.stand`` the arm's stands), e.g.
``--set act.approach.views=3``.
"""

from __future__ import annotations

import dataclasses
import json
import tomllib
import typing
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from agent.app.config_bounds import check_bounds
from agent.eqa.stopping import StopConfig
from agent.mapping.occupancy import OccupancyConfig
from agent.mapping.semantic_map import SemanticValueConfig
from agent.planning.frontier_plan import ExploreConfig
from agent.planning.prompt_points import PromptPointConfig
from agent.planning.semantic import FrontierWeightConfig
from agent.vlm.settings import VLMSettings
from behaviours.look_inside import LookInsideConfig


class ConfigError(ValueError):
    """A configuration value or file that cannot be used; the text names the key."""


@dataclass(frozen=True)
class CameraSettings:
    """The head camera the world renders for the agent: image size in pixels, horizontal field of view."""

    width: int = 320
    height: int = 240
    hfov_deg: float = 90.0


@dataclass(frozen=True)
class BusSettings:
    """The agent's side of the wire: where `homebot watch` reaches it, how long it waits on the world,
    and a Zenoh configuration file (TLS, access control: docs/hosts.md) its sessions and the worlds
    it starts open with ("": none; ``--zenoh-config FILE``)."""

    listen: tuple[str, ...] = ("tcp/127.0.0.1:7450",)
    query_timeout_s: float = 10.0
    move_timeout_s: float = 30.0
    world_start_timeout_s: float = 60.0
    zenoh_config: str = ""


@dataclass(frozen=True)
class EpisodeSettings:
    """An episode's limits: its step budget, wall time, how its ticks are paced, and how long one VLM
    call may take. A tree that waits (on the world, on the VLM) ticks again the moment the reply is
    in, or after ``max_wait_s`` if none comes; ``tick_period_s`` (0: none) is the least time between
    ticks, to slow an episode down on purpose."""

    budget: int = 0  # 0: the scenario's own budget, int(3·sqrt(area))
    max_seconds: float = 900.0
    tick_period_s: float = 0.0
    max_wait_s: float = 0.05
    vlm_timeout_s: float = 30.0


@dataclass(frozen=True)
class SkillPlug:
    """An installed skill put into the EQA tree: ``skill`` (its registered name) runs right after
    the node called ``after`` (a node name as `homebot watch` shows it), each time that node's
    branch reaches it, with ``ports`` bound (values, or ``"{key}"`` of the blackboard); ``name``
    names its node (default: the skill's class name)."""

    skill: str = ""
    after: str = ""
    ports: dict[str, Any] = field(default_factory=dict)
    name: str = ""


@dataclass(frozen=True)
class TreeSettings:
    """What the EQA tree holds beyond its own behaviours: ``skills`` put into it (see `SkillPlug`);
    in TOML, one ``[[tree.skills]]`` table each."""

    skills: tuple[SkillPlug, ...] = ()


@dataclass(frozen=True)
class RaySettings:
    """What an evaluation's episode asks of a Ray cluster (``--ray``, docs/scale.md): the CPUs it
    uses, its agent's process and the world process it starts beside it together
    (``cpus_per_episode``), or its agent's alone when it joins a running world elsewhere
    (``--worlds``: ``cpus_per_agent``). Ray starts no more episodes on a node than its CPUs hold,
    so the figures are what keep a node from being oversubscribed; fractions are allowed (1.5: a
    world that mostly waits on its agent)."""

    cpus_per_episode: float = 2.0
    cpus_per_agent: float = 1.0


@dataclass(frozen=True)
class Config:
    """Every setting of a run, one section per part of the agent; ``[section]`` in TOML, ``section.key`` with --set."""

    camera: CameraSettings = field(default_factory=CameraSettings)
    bus: BusSettings = field(default_factory=BusSettings)
    episode: EpisodeSettings = field(default_factory=EpisodeSettings)
    map: OccupancyConfig = field(default_factory=OccupancyConfig)
    explore: ExploreConfig = field(default_factory=ExploreConfig)
    prompt_points: PromptPointConfig = field(default_factory=PromptPointConfig)
    semantic_values: SemanticValueConfig = field(default_factory=SemanticValueConfig)
    frontier_weights: FrontierWeightConfig = field(default_factory=FrontierWeightConfig)
    vlm: VLMSettings = field(default_factory=VLMSettings)
    stop: StopConfig = field(default_factory=StopConfig)
    act: LookInsideConfig = field(default_factory=LookInsideConfig)
    tree: TreeSettings = field(default_factory=TreeSettings)
    ray: RaySettings = field(default_factory=RaySettings)


def load_config(path: Path | None = None, overrides: list[str] | None = None, base: Config | None = None) -> Config:
    """Settings for a run: ``base``, then a TOML file, then ``key=value`` overrides, later winning.

    Args:
        path: a TOML file of settings, its tables the sections (``[map.tsdf]``), or None.
        overrides: ``dotted.key=value`` items, each value JSON or else a bare string.
        base: the settings to start from (default: the defaults).

    Returns:
        The settings, every value type-checked, within its range, and each section's own checks passed.

    Raises:
        ConfigError: an unreadable file, a malformed override, an unknown key or a bad value; the
            text names the dotted key.
    """
    config = base or Config()
    if path is not None:
        config = merge(config, _read_toml(Path(path)))
    for item in overrides or []:
        key, sep, raw = item.partition("=")
        if not sep or not key:
            raise ConfigError(f"config override {item!r}: expected key=value, e.g. map.resolution=0.05")
        config = merge(config, _nest(key.strip().split("."), _parse_value(raw.strip())))
    return config


def merge(config: Any, data: dict[str, Any], prefix: str = "") -> Any:
    """Apply a nested table of values to a settings dataclass, checking each against its field's type.

    Args:
        config: a frozen settings dataclass (a section, or the whole `Config`).
        data: field name -> value, a nested table for a field that is itself a dataclass; a table
            given to a mapping field (``act.min_look``) updates the keys it names.
        prefix: the dotted name of ``config`` with a trailing dot, for messages ("" at the top).

    Returns:
        A copy of ``config`` with the values applied.

    Raises:
        ConfigError: an unknown key, a value of the wrong type or out of its range
            (`agent.app.config_bounds`), or one the section's checks refuse.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"config: {prefix.rstrip('.') or 'top level'}: expected a table")
    fields = {f.name: f for f in dataclasses.fields(config)}
    hints = typing.get_type_hints(type(config))
    changes = {}
    for key, value in data.items():
        name = f"{prefix}{key}"
        if key not in fields:
            raise ConfigError(f"config: unknown key {name} (known here: {', '.join(sorted(fields))})")
        current = getattr(config, key)
        if dataclasses.is_dataclass(current):
            changes[key] = merge(current, value, f"{name}.")
            continue
        coerced = _coerce(name, value, hints[key])
        changes[key] = {**current, **coerced} if isinstance(current, dict) else coerced
        try:
            check_bounds(name, changes[key])
        except ValueError as error:
            raise ConfigError(f"config: {error}") from None
    try:
        return dataclasses.replace(config, **changes)
    except ValueError as error:
        raise ConfigError(f"config: {error}") from None


def _coerce(name: str, value: Any, hint: Any) -> Any:
    origin = typing.get_origin(hint)
    if hint is bool:
        if isinstance(value, bool):
            return value
    elif hint is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif hint is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
    elif hint is str:
        if isinstance(value, str):
            return value
    elif dataclasses.is_dataclass(hint):
        if isinstance(value, dict):
            return merge(hint(), value, f"{name}.")
    elif origin is tuple:
        args = typing.get_args(hint)
        if isinstance(value, (list, tuple)):
            if len(args) == 2 and args[1] is Ellipsis:
                return tuple(_coerce(f"{name}[{i}]", v, args[0]) for i, v in enumerate(value))
            if len(value) == len(args):
                return tuple(_coerce(f"{name}[{i}]", v, a) for i, (v, a) in enumerate(zip(value, args)))
    elif origin is dict:
        key_type, value_type = typing.get_args(hint)
        if isinstance(value, dict):
            if value_type is Any:  # values a later check types (a skill's ports)
                return {_coerce(f"{name} key", k, key_type): v for k, v in value.items()}
            return {_coerce(f"{name} key", k, key_type): _coerce(f"{name}.{k}", v, value_type)
                    for k, v in value.items()}
    type_name = getattr(hint, "__name__", str(hint)).replace("float", "number").replace("dict", "table")
    raise ConfigError(f"config: {name}: expected {type_name}, got {_shown(value)}")


def _shown(value: Any) -> str:
    """``repr(value)``, shortened to 60 characters."""
    text = repr(value)
    return text if len(text) <= 60 else f"{text[:45]}…{text[-10:]}"


def _read_toml(path: Path) -> dict[str, Any]:
    """The tables of a settings file; a file that cannot be read, is not UTF-8 or not TOML (an
    integer of thousands of digits, nesting past Python's limit) is a ConfigError naming it."""
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as error:
        line = error.object[:error.start].count(b"\n") + 1
        raise ConfigError(f"config file {path}: not UTF-8 text (line {line}, byte {error.start}: {error.reason})") from None
    except OSError as error:
        raise ConfigError(f"config file {path}: cannot be read ({error.strerror or error})") from None
    try:
        return tomllib.loads(text)
    except ValueError as error:  # tomllib.TOMLDecodeError, or an integer too long to convert
        raise ConfigError(f"config file {path}: not TOML: {error}") from None
    except RecursionError:
        raise ConfigError(f"config file {path}: not TOML that can be read: nested too deeply") from None


def _parse_value(raw: str) -> Any:
    """An override's value: JSON when it parses as JSON, else the bare string."""
    try:
        return json.loads(raw)
    except (ValueError, RecursionError):  # not JSON (or a number or nesting JSON cannot hold): a word
        return raw


def _nest(keys: list[str], value: Any) -> dict[str, Any]:
    for key in reversed(keys):
        value = {key: value}
    return value
