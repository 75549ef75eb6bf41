"""Which calibration a run uses, and whether it fits the run's settings.

The calibration file itself (`agent.eqa.calibration`) is plain data; what a run's policy and VLM
are comes from the settings, which only the composition root knows. Here both meet: what the scores
of a run with these settings depend on (`made_with`), the file that ships for them, and the refusal
of a file made with other settings.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from pathlib import Path
from typing import Any

from agent.app.config import Config
from agent.eqa.calibration import Calibration, CalibrationError, differences, read_calibration
from agent.eqa.stopping import StopRuleName
from agent.app.runtime.record import write_json_atomic

SHIPPED_DIR = Path(__file__).resolve().parents[2] / "data"


def made_with(config: Config) -> dict[str, Any]:
    """What the scores depend on: the exploration policy, the map, the camera and the VLM.

    Settings that change how but not what the VLM answers (a server's URL, timeouts, retries) are
    left out, so moving a server does not invalidate a calibration. So is the step budget: a robot
    with fewer steps than the calibration episodes had keeps the guarantee (its set can only be
    larger), which docs/stopping.md spells out.

    Args:
        config: the settings.

    Returns:
        Those settings, as plain data.
    """
    vlm: dict[str, Any] = {"backend": config.vlm.backend}
    if config.vlm.backend == "sim":
        vlm["sim"] = dataclasses.asdict(config.vlm.sim)
    elif config.vlm.backend == "openai":
        vlm["openai"] = {"model": config.vlm.openai.model}
    else:
        vlm["hf"] = {"path": config.vlm.hf.path}
    return _plain({
        "explore": dataclasses.asdict(config.explore),
        "frontier_weights": dataclasses.asdict(config.frontier_weights),
        "semantic_values": dataclasses.asdict(config.semantic_values),
        "prompt_points": dataclasses.asdict(config.prompt_points),
        "map": dataclasses.asdict(config.map),
        "camera": dataclasses.asdict(config.camera),
        "vlm": vlm,
    })


def _plain(data: Any) -> Any:
    """JSON's view of ``data`` (tuples become lists), so a loaded file compares equal to a config."""
    return json.loads(json.dumps(data))


def mismatches(recorded: dict[str, Any], config: Config) -> list[str]:
    """The dotted settings where ``config`` differs from ``recorded``, a `made_with` of earlier runs.

    Args:
        recorded: the settings recorded.
        config: the settings now.

    Returns:
        One line per difference.
    """
    return differences(recorded, made_with(config))


def write_calibration(path: Path, calibration: Calibration) -> None:
    """Write a calibration file atomically, as compact JSON.

    Args:
        path: the file.
        calibration: the calibration.
    """
    write_json_atomic(Path(path), calibration.to_json(), indent=None)


def shipped_calibration(config: Config) -> Path:
    """The calibration shipped with homebot for this exploration method and VLM backend.

    Args:
        config: the settings (the method and the backend).

    Returns:
        The file's path (it may not exist).
    """
    return SHIPPED_DIR / f"calibration-{config.explore.method}-{config.vlm.backend}.json"


def calibration_for(config: Config) -> tuple[Calibration, Path]:
    """The calibration this run's `stop` settings name, refused when it does not fit the policy.

    Args:
        config: the settings.

    Returns:
        The calibration and its path.

    Raises:
        CalibrationError: the file ``stop.calibration`` names is missing, none ships for these
            settings, or it does not fit them.
    """
    path = Path(config.stop.calibration) if config.stop.calibration else shipped_calibration(config)
    if config.stop.calibration and not path.is_file():
        raise CalibrationError(f"stop.calibration: {path}: no such file (make one with `homebot calibrate --suite "
                               "SUITE --out FILE`, or stop at the budget with --stop budget)")
    if not path.exists() and not config.stop.calibration:
        shipped = ", ".join(sorted(p.name for p in SHIPPED_DIR.glob("calibration-*.json"))) or "none"
        raise CalibrationError(
            f"no calibration ships for explore.method={config.explore.method} with vlm.backend="
            f"{config.vlm.backend} (shipped: {shipped}). Make one with `homebot calibrate --suite SUITE "
            "--out FILE` and pass --set stop.calibration=FILE, or stop at the budget with --stop budget."
        )
    calibration = _read(path)
    check_fits(calibration, path, config)
    return calibration, path


def _read(path: Path) -> Calibration:
    """`read_calibration`, once per process for a file unchanged since: `homebot run` checks its
    calibration before it starts the world and makes its stopping rule from it after."""
    try:
        stat = path.stat()
    except OSError:
        return read_calibration(path)  # which says why it cannot be read
    return _read_unchanged(path.resolve(), stat.st_mtime_ns, stat.st_size)


@functools.lru_cache(maxsize=4)
def _read_unchanged(path: Path, mtime_ns: int, size: int) -> Calibration:
    return read_calibration(path)


def stop_calibration(config: Config) -> tuple[Calibration, Path] | None:
    """The calibration the run's stopping rule needs, checked against the settings; the conformal
    rule (``stop.rule=cp``) needs one, the others none. Cheap, so a command checks it before it
    starts a world.

    Args:
        config: the settings.

    Returns:
        The calibration and its path, or None for a rule that needs none.

    Raises:
        CalibrationError: the calibration is missing, unreadable, or does not fit the settings.
    """
    return calibration_for(config) if config.stop.rule == StopRuleName.CP else None


def check_fits(calibration: Calibration, path: Path, config: Config) -> None:
    """Refuse a calibration made with another policy or VLM, naming every difference, unless the
    config says to accept it.

    Args:
        calibration: the calibration.
        path: its file, named in the error.
        config: the settings now.

    Raises:
        CalibrationError: naming the differences.
    """
    differences = mismatches(calibration.made_with, config)
    if differences and not config.stop.accept_mismatched_calibration:
        listed = "\n  ".join(differences)
        raise CalibrationError(
            f"calibration file {path} was made with another policy or VLM, so its guarantee does not hold here:\n"
            f"  {listed}\n"
            "Calibrate this policy with `homebot calibrate --suite SUITE --out FILE` (same --set options) "
            "and pass --set stop.calibration=FILE, stop at the budget with --stop budget, "
            "or accept it anyway with --set stop.accept_mismatched_calibration=true."
        )
