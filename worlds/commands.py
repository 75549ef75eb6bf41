"""Checking world command requests field by field, before anything touches the simulator.

Every problem raises `RequestError` with the field's full name (``move_base.path[3]``) and what is
wrong with it, which the command server sends back to the client as the error reply. Unknown
fields and unknown arrays are rejected too, so a misspelt option fails loudly instead of being
ignored. Every number is bounded, whatever its type or size: an integer of any length is compared,
never converted, before it is accepted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from worlds.bus.rpc import RequestError
from worlds.freespace import clearance
from worlds.home import ROOM_COUNT, HomeSpec
from worlds.robot import ROBOT_RADIUS
from worlds.robot_arm import CAMERAS, ArmSpec
from worlds.scenario import Scenario
from worlds.spec import load_spec
from worlds.spec_fields import SpecError
from worlds.tabletop import TASKS
from worlds.bus.questions import LETTERS

MAX_WAYPOINTS = 500
#: Waypoints further than this from the origin are certainly a mistake (homes are ~10 m across).
MAX_COORDINATE_M = 1000.0
#: Headings (a move's final yaw, a start pose's) in radians lie within ±this: any heading, turned
#: by another half or whole turn as callers do (a facing plus pi).
MAX_YAW = 4 * math.pi
#: How far a start pose's disc may reach into an obstacle: rounding, not overlap.
START_SLACK_M = 0.005
MAX_SEED = 2**63 - 1
#: The most steps a scenario may grant (a home's own budget is 3·sqrt(area), a few dozen).
MAX_BUDGET = 10_000
#: The longest text of a scenario (its question, a choice, its kind).
MAX_TEXT = 1000
#: The slots a scenario's target may name, each a word or null.
TARGET_SLOTS = ("category", "colour", "room", "container", "appliance")
#: The most problems of a scene one error reply lists (the rest are counted).
MAX_SCENE_ERRORS = 20
#: The arrays each command takes; the others take none.
ARRAYS = {"arm_trajectory": ("samples",)}
#: Trajectory sampling periods allowed, in seconds, and the longest trajectory one query may run.
DT_RANGE = (0.001, 1.0)
MAX_TRAJECTORY_S = 120.0
MAX_SAMPLES = 20_000
#: Slack on the velocity limit between consecutive samples (rounding in the sampler, not speeding).
VELOCITY_SLACK = 1.05
GRIPPER_ACTIONS = ("open", "close")


def _only(meta: dict[str, Any], verb: str, allowed: tuple[str, ...]) -> None:
    unknown = sorted(set(meta) - set(allowed))
    if unknown:
        expected = ", ".join(allowed) if allowed else "no fields"
        raise RequestError(f"{verb}.{unknown[0]}: unknown field (expected {expected})")


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value: Any) -> bool:
    """A finite number (not a boolean); an integer of any size is finite, and is never converted here."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    return isinstance(value, int) or math.isfinite(value)


def _show(value: Any) -> str:
    """The value as an error message shows it: short, even for an integer of thousands of digits."""
    if _is_int(value) and abs(value) >= 10**20:
        return f"an integer of {value.bit_length()} bits"
    text = repr(value) if not isinstance(value, (list, dict)) or len(value) < 20 else f"a {type(value).__name__} " \
        f"of {len(value)} items"
    return text if len(text) <= 80 else f"{text[:77]}..."


def check_arrays(verb: str, arrays: dict[str, np.ndarray]) -> None:
    """Refuse arrays the command ``verb`` does not take (`ARRAYS`).

    Args:
        verb: the command.
        arrays: the request's arrays.

    Raises:
        RequestError: naming the first unknown array.
    """
    allowed = ARRAYS.get(verb, ())
    unknown = sorted(set(arrays) - set(allowed))
    if unknown:
        expected = f"expected only {', '.join(allowed)}" if allowed else "this command takes no arrays"
        raise RequestError(f"{verb}.arrays.{unknown[0]}: unknown array ({expected})")


@dataclass(frozen=True)
class ResetRequest:
    """What to build: the home of ``seed`` or the given ``scene``, and its scenario or the given one;
    or, with ``tabletop`` (a task of `worlds.tabletop.TASKS`), that task's variant ``seed``."""

    seed: int
    n_rooms: int | None
    home: HomeSpec | None
    scenario: Scenario | None
    tabletop: str | None = None


def parse_reset(meta: dict[str, Any]) -> ResetRequest:
    """From ``{"seed": int >= 0, "n_rooms": optional int, "scene": optional spec, "scenario": optional}``
    or ``{"seed": int >= 0, "tabletop": task}``.

    Args:
        meta: the request's metadata.

    Returns:
        The request.

    Raises:
        RequestError: naming the field that is wrong.
    """
    _only(meta, "reset", ("seed", "n_rooms", "scene", "scenario", "tabletop"))
    if "seed" not in meta:
        raise RequestError("reset.seed: missing (an integer >= 0 is required)")
    seed = meta["seed"]
    if not _is_int(seed):
        raise RequestError(f"reset.seed: expected an integer, got {type(seed).__name__}")
    if not 0 <= seed <= MAX_SEED:
        raise RequestError(f"reset.seed: {_show(seed)} must lie in 0..{MAX_SEED}")
    n_rooms = meta.get("n_rooms")
    if n_rooms is not None:
        if not _is_int(n_rooms):
            raise RequestError(f"reset.n_rooms: expected an integer or null, got {type(n_rooms).__name__}")
        if not ROOM_COUNT[0] <= n_rooms <= ROOM_COUNT[1]:
            raise RequestError(f"reset.n_rooms: {_show(n_rooms)} must lie in {ROOM_COUNT[0]}..{ROOM_COUNT[1]}")
    home = None
    if meta.get("scene") is not None:
        try:
            home = load_spec(meta["scene"])
        except SpecError as error:
            shown = [f"reset.scene.{line}" for line in error.errors[:MAX_SCENE_ERRORS]]
            more = len(error.errors) - len(shown)
            raise RequestError("; ".join(shown) + (f"; and {more} more problems" if more > 0 else "")) from None
    scenario = _parse_scenario(meta["scenario"]) if meta.get("scenario") is not None else None
    tabletop = meta.get("tabletop")
    if tabletop is not None:
        if tabletop not in TASKS:
            raise RequestError(f"reset.tabletop: {_show(tabletop)} is not one of {', '.join(TASKS)}")
        home_fields = [name for name in ("n_rooms", "scene", "scenario") if meta.get(name) is not None]
        if home_fields:
            raise RequestError(f"reset.tabletop: cannot be combined with {home_fields[0]} (that is for homes)")
    return ResetRequest(seed, n_rooms, home, scenario, tabletop)


def _parse_scenario(data: Any) -> Scenario:
    """A scenario sent by the client, checked field by field (where it starts is checked against
    the home by `check_start_pose`)."""
    where = "reset.scenario"
    if not isinstance(data, dict):
        raise RequestError(f"{where}: expected an object")
    expected = {f.name for f in fields(Scenario)}
    mismatched = sorted(expected ^ set(data))
    if mismatched:
        name = mismatched[0]
        raise RequestError(f"{where}.{name}: {'missing' if name in expected else 'unknown field'}")
    for name in ("question", "answer_text", "kind", "asks"):
        if not isinstance(data[name], str) or len(data[name]) > MAX_TEXT:
            raise RequestError(f"{where}.{name}: expected a string of at most {MAX_TEXT} characters")
    if not (isinstance(data["choices"], list) and len(data["choices"]) == 4
            and all(isinstance(c, str) and len(c) <= MAX_TEXT for c in data["choices"])):
        raise RequestError(f"{where}.choices: expected four strings of at most {MAX_TEXT} characters")
    if data["answer"] not in LETTERS or data["choices"][LETTERS.index(data["answer"])] != data["answer_text"]:
        raise RequestError(f"{where}.answer: must be a letter A-D naming the choice equal to answer_text")
    for name, most in (("seed", MAX_SEED), ("budget", MAX_BUDGET)):
        least = 0 if name == "seed" else 1
        if not _is_int(data[name]) or not least <= data[name] <= most:
            raise RequestError(f"{where}.{name}: {_show(data[name])} is not an integer in {least}..{most}")
    pose = data["start_pose"]
    if not (isinstance(pose, list) and len(pose) == 3 and all(_is_number(v) for v in pose)):
        raise RequestError(f"{where}.start_pose: expected [x, y, yaw] of finite numbers")
    if any(abs(v) > MAX_COORDINATE_M for v in pose[:2]) or abs(pose[2]) > MAX_YAW:
        raise RequestError(f"{where}.start_pose: {_show(pose)} must have x and y within ±{MAX_COORDINATE_M:g} m "
                           f"and yaw within ±4π")
    target = data["target"]
    if not isinstance(target, dict):
        raise RequestError(f"{where}.target: expected an object")
    for name, value in target.items():
        if name not in TARGET_SLOTS:
            raise RequestError(f"{where}.target.{name[:40]}: unknown slot (expected {', '.join(TARGET_SLOTS)})")
        if value is not None and not (isinstance(value, str) and len(value) <= MAX_TEXT):
            raise RequestError(f"{where}.target.{name}: expected a word or null, got {_show(value)}")
    return Scenario.from_dict({**data, "start_pose": [float(v) for v in pose],
                               "target": {name: target.get(name) for name in TARGET_SLOTS}})


def check_start_pose(home: HomeSpec, pose: tuple[float, float, float]) -> None:
    """Refuse a scenario's start pose outside the home's rooms or where the robot would overlap a
    wall, furniture or an object on the floor.

    Args:
        home: the home the scenario is for.
        pose: the start pose (x, y, yaw).

    Raises:
        RequestError: naming ``reset.scenario.start_pose`` and what is in the way.
    """
    where = "reset.scenario.start_pose"
    x, y, _ = pose
    if home.room_at(x, y) is None:
        bounds = ", ".join(f"{v:g}" for v in home.bounds)
        raise RequestError(f"{where}: ({x:g}, {y:g}) is in none of the home's rooms (its bounds: [{bounds}])")
    gap = clearance(home, x, y)
    if gap < ROBOT_RADIUS - START_SLACK_M:
        raise RequestError(f"{where}: ({x:g}, {y:g}) is {gap:.2f} m from a wall, furniture or floor object; "
                           f"the robot needs {ROBOT_RADIUS:g} m of free space around it")


def parse_observe(meta: dict[str, Any]) -> str:
    """The camera to render, from ``{"camera": "head" (default) | "wrist"}``.

    Args:
        meta: the request's metadata.

    Returns:
        The camera's name.

    Raises:
        RequestError: an unknown key or camera.
    """
    _only(meta, "observe", ("camera",))
    camera = meta.get("camera", "head")
    if camera not in CAMERAS:
        raise RequestError(f"observe.camera: {_show(camera)} is not one of {', '.join(CAMERAS)}")
    return camera


def parse_description(meta: dict[str, Any]) -> None:
    """Check that the ``description`` request carries no fields.

    Args:
        meta: the request's metadata.

    Raises:
        RequestError: an unknown key.
    """
    _only(meta, "description", ())


def parse_move_base(meta: dict[str, Any]) -> tuple[list[tuple[float, float]], float | None]:
    """(waypoints, final yaw or None) from ``{"path": [[x, y], ...], "yaw": optional radians}``.

    Args:
        meta: the request's metadata.

    Returns:
        The waypoints and the yaw.

    Raises:
        RequestError: naming the field that is wrong.
    """
    _only(meta, "move_base", ("path", "yaw"))
    if "path" not in meta:
        raise RequestError("move_base.path: missing (a list of [x, y] waypoints is required)")
    path = meta["path"]
    if not isinstance(path, list):
        raise RequestError(f"move_base.path: expected a list of [x, y] waypoints, got {type(path).__name__}")
    if not 1 <= len(path) <= MAX_WAYPOINTS:
        raise RequestError(f"move_base.path: has {len(path)} waypoints, expected 1..{MAX_WAYPOINTS}")
    waypoints = []
    for index, point in enumerate(path):
        if not (isinstance(point, list) and len(point) == 2 and all(_is_number(v) for v in point)):
            raise RequestError(f"move_base.path[{index}]: expected [x, y] of finite numbers, got {_show(point)}")
        if any(abs(v) > MAX_COORDINATE_M for v in point):
            raise RequestError(f"move_base.path[{index}]: coordinates must lie within ±{MAX_COORDINATE_M:g} m")
        waypoints.append((float(point[0]), float(point[1])))
    yaw = meta.get("yaw")
    if yaw is not None and not (_is_number(yaw) and abs(yaw) <= MAX_YAW):
        raise RequestError(f"move_base.yaw: expected a finite number of radians within ±4π or null, got {_show(yaw)}")
    return waypoints, None if yaw is None else float(yaw)


def parse_arm_state(meta: dict[str, Any]) -> None:
    """Check that the ``arm_state`` request carries no fields.

    Args:
        meta: the request's metadata.

    Raises:
        RequestError: an unknown key.
    """
    _only(meta, "arm_state", ())


def parse_episode_report(meta: dict[str, Any]) -> None:
    """Check that the ``episode_report`` request carries no fields.

    Args:
        meta: the request's metadata.

    Raises:
        RequestError: an unknown key.
    """
    _only(meta, "episode_report", ())


def parse_gripper(meta: dict[str, Any]) -> bool:
    """Whether to close the gripper, from ``{"action": "open" | "close"}``.

    Args:
        meta: the request's metadata.

    Returns:
        Whether to close.

    Raises:
        RequestError: the action is missing or unknown.
    """
    _only(meta, "gripper", ("action",))
    action = meta.get("action")
    if action is None:
        raise RequestError("gripper.action: missing (\"open\" or \"close\" is required)")
    if action not in GRIPPER_ACTIONS:
        raise RequestError(f"gripper.action: {_show(action)} is not one of {', '.join(GRIPPER_ACTIONS)}")
    return action == "close"


@dataclass(frozen=True)
class TrajectoryRequest:
    """Joint samples (N, joints) in `ArmSpec` order, one every ``dt`` seconds."""

    samples: np.ndarray
    dt: float
    stop_on_contact: bool
    stop_on_new_contact: bool = False


def parse_arm_trajectory(meta: dict[str, Any], arrays: dict[str, np.ndarray], arm: ArmSpec) -> TrajectoryRequest:
    """From ``{"dt": seconds, "stop_on_contact": optional bool, "stop_on_new_contact": optional bool}``
    and the float array ``samples`` (N, joints). At most one of the two may be true: the first stops
    the motion on any contact, the second only on one the arm did not begin it with.

    Every sample must be finite and within the joints' position limits, and no joint may move faster
    than its velocity limit between consecutive samples. Where the first sample may start is the
    world's to check: it depends on where the arm is.

    Args:
        meta: the request's metadata.
        arrays: the request's arrays.
        arm: the arm's joints and limits.

    Returns:
        The request.

    Raises:
        RequestError: naming the field or sample that is wrong.
    """
    where = "arm_trajectory"
    _only(meta, where, ("dt", "stop_on_contact", "stop_on_new_contact"))
    check_arrays(where, arrays)
    dt = meta.get("dt")
    if dt is None:
        raise RequestError(f"{where}.dt: missing (the sampling period in seconds is required)")
    if not _is_number(dt) or not DT_RANGE[0] <= dt <= DT_RANGE[1]:
        raise RequestError(f"{where}.dt: {_show(dt)} must be a number of seconds in [{DT_RANGE[0]:g}, {DT_RANGE[1]:g}]")
    stops = {}
    for field in ("stop_on_contact", "stop_on_new_contact"):
        stops[field] = meta.get(field, False)
        if not isinstance(stops[field], bool):
            raise RequestError(f"{where}.{field}: expected true or false, got {_show(stops[field])}")
    if all(stops.values()):
        raise RequestError(f"{where}.stop_on_new_contact: true together with stop_on_contact; at most one may be "
                           f"(stop on any contact, or only on one the arm did not begin the motion with)")
    if "samples" not in arrays:
        raise RequestError(f"{where}.samples: missing (a float array of shape (N, {len(arm.joints)}) is required)")
    samples = arrays["samples"]
    if samples.dtype.kind != "f":
        raise RequestError(f"{where}.samples: dtype {samples.dtype.name} is not a float type (float32 or float64)")
    if samples.ndim != 2 or samples.shape[1] != len(arm.joints):
        raise RequestError(f"{where}.samples: shape {list(samples.shape)} is not (N, {len(arm.joints)}): one column "
                           f"per joint of {', '.join(arm.names)}")
    count = samples.shape[0]
    if not 1 <= count <= MAX_SAMPLES or count * dt > MAX_TRAJECTORY_S:
        raise RequestError(f"{where}.samples: {count} samples of {dt:g} s; expected 1..{MAX_SAMPLES} samples "
                           f"lasting at most {MAX_TRAJECTORY_S:g} s")
    samples = samples.astype(np.float64)
    bad = np.argwhere(~np.isfinite(samples))
    if len(bad):
        row, column = bad[0]
        raise RequestError(f"{where}.samples[{row}][{column}]: {samples[row, column]} is not finite")
    lower, upper = arm.column("lower"), arm.column("upper")
    bad = np.argwhere((samples < lower) | (samples > upper))
    if len(bad):
        row, column = bad[0]
        raise RequestError(f"{where}.samples[{row}][{column}]: {samples[row, column]:.4f} is outside "
                           f"{arm.names[column]}'s limits [{lower[column]:g}, {upper[column]:g}]")
    step = np.abs(np.diff(samples, axis=0))
    fastest = arm.column("velocity") * dt * VELOCITY_SLACK
    bad = np.argwhere(step > fastest)
    if len(bad):
        row, column = bad[0]
        raise RequestError(f"{where}.samples[{row + 1}][{column}]: moves {step[row, column]:.4f} in {dt:g} s, faster "
                           f"than {arm.names[column]}'s {arm.joints[column].velocity:g} per second")
    return TrajectoryRequest(samples, float(dt), stops["stop_on_contact"], stops["stop_on_new_contact"])
