"""The calibration file: the non-conformity scores of N calibration episodes and what made them.

Conformal prediction promises coverage only for test episodes drawn like the calibration ones, so
the file records the exploration policy and VLM the scores came from, and a run with a different
policy or VLM refuses it (`mismatches`). A checksum over the content catches a file edited or cut
short by hand.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agent.config import Config
from agent.eqa.answers import steps_from_records
from agent.eqa.conformal import conformal_quantile, nonconformity
from agent.runtime.record import write_json_atomic

CALIBRATION_FORMAT = "homebot-calibration"
CALIBRATION_VERSION = 1
SHIPPED_DIR = Path(__file__).resolve().parent.parent / "data"


class CalibrationError(ValueError):
    """A calibration file that cannot be used; the text names the file and the problem."""


def made_with(config: Config) -> dict[str, Any]:
    """What the scores depend on: the exploration policy, the map, the camera and the VLM.

    Settings that change how but not what the VLM answers (a server's URL, timeouts, retries) are
    left out, so moving a server does not invalidate a calibration. So is the step budget: a robot
    with fewer steps than the calibration episodes had keeps the guarantee (its set can only be
    larger), which docs/stopping.md spells out.
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


def suite_identity(path: Path, entries: int) -> dict[str, Any]:
    return {"file": Path(path).name, "sha256": hashlib.sha256(Path(path).read_bytes()).hexdigest(), "entries": entries}


@dataclass(frozen=True)
class CalibrationEpisode:
    """One calibration episode: its truth, its steps' scores and its non-conformity κ."""

    id: str
    seed: int
    ground_truth: str
    step_scores: list[dict[str, Any]]

    @property
    def kappa(self) -> float:
        return nonconformity(steps_from_records(self.step_scores), self.ground_truth)


@dataclass(frozen=True)
class Calibration:
    made_with: dict[str, Any]
    suite: dict[str, Any]
    episodes: list[CalibrationEpisode]
    failed: list[str]  # ids of calibration episodes that failed and so give no score
    created: str = ""

    @property
    def kappas(self) -> list[float]:
        return [episode.kappa for episode in self.episodes]

    def q_hat(self, epsilon: float) -> float:
        """q̂(ε) over this file's scores (+∞ when N is too small for 1 − ε)."""
        return conformal_quantile(self.kappas, epsilon)

    def to_json(self) -> dict[str, Any]:
        body = {
            "format": CALIBRATION_FORMAT,
            "version": CALIBRATION_VERSION,
            "created": self.created or time.strftime("%Y-%m-%dT%H:%M:%S%z"),
            "made_with": self.made_with,
            "suite": self.suite,
            "n": len(self.episodes),
            "failed": self.failed,
            "episodes": [
                {"id": e.id, "seed": e.seed, "ground_truth": e.ground_truth, "kappa": round(e.kappa, 6),
                 "step_scores": e.step_scores}
                for e in self.episodes
            ],
        }
        return {**body, "checksum": _checksum(body)}


def _checksum(body: dict[str, Any]) -> str:
    canonical = json.dumps(body, sort_keys=True, ensure_ascii=False, separators=(",", ":"))
    return "sha256:" + hashlib.sha256(canonical.encode("utf-8")).hexdigest()


def write_calibration(path: Path, calibration: Calibration) -> None:
    write_json_atomic(Path(path), calibration.to_json(), indent=None)


def read_calibration(path: Path) -> Calibration:
    """Load and check a calibration file; every problem is named with the file."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise CalibrationError(f"calibration file {path}: not found (make one with `homebot calibrate`)") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise CalibrationError(f"calibration file {path}: cannot be read as JSON: {error}") from None
    if not isinstance(data, dict) or data.get("format") != CALIBRATION_FORMAT:
        raise CalibrationError(f"calibration file {path}: not a {CALIBRATION_FORMAT} file")
    if data.get("version") != CALIBRATION_VERSION:
        raise CalibrationError(f"calibration file {path}: version {data.get('version')!r}, "
                               f"this homebot reads version {CALIBRATION_VERSION}")
    body = {key: value for key, value in data.items() if key != "checksum"}
    if data.get("checksum") != _checksum(body):
        raise CalibrationError(f"calibration file {path}: checksum does not match its content "
                               "(edited or truncated); calibrate again")
    try:
        episodes = [CalibrationEpisode(e["id"], int(e["seed"]), e["ground_truth"], e["step_scores"])
                    for e in data["episodes"]]
        calibration = Calibration(data["made_with"], data["suite"], episodes, list(data["failed"]), data["created"])
        kappas = calibration.kappas  # computed now, so a bad episode is named here rather than at q̂
    except (KeyError, TypeError, ValueError) as error:
        raise CalibrationError(f"calibration file {path}: malformed entry ({error!r})") from None
    if any(not 1.0 <= kappa <= 2.0 for kappa in kappas):
        raise CalibrationError(f"calibration file {path}: a score lies outside [1, 2], so an f̂ or Rel "
                               "was not a probability")
    if not episodes:
        raise CalibrationError(f"calibration file {path}: holds no episode")
    return calibration


def mismatches(recorded: dict[str, Any], config: Config) -> list[str]:
    """The dotted settings where ``config`` differs from ``recorded``, a `made_with` of earlier runs."""
    return _differences(recorded, made_with(config))


def _differences(made: Any, now: Any, prefix: str = "") -> list[str]:
    if isinstance(made, dict) and isinstance(now, dict):
        found = []
        for key in sorted(set(made) | set(now)):
            found += _differences(made.get(key), now.get(key), f"{prefix}{key}.")
        return found
    if made != now:
        return [f"{prefix.rstrip('.')}: calibrated with {made!r}, this run uses {now!r}"]
    return []


def shipped_calibration(config: Config) -> Path:
    """The calibration shipped with homebot for this exploration method and VLM backend."""
    return SHIPPED_DIR / f"calibration-{config.explore.method}-{config.vlm.backend}.json"


def calibration_for(config: Config) -> tuple[Calibration, Path]:
    """The calibration this run's `stop` settings name, refused when it does not fit the policy."""
    path = Path(config.stop.calibration) if config.stop.calibration else shipped_calibration(config)
    if not path.exists() and not config.stop.calibration:
        shipped = ", ".join(sorted(p.name for p in SHIPPED_DIR.glob("calibration-*.json"))) or "none"
        raise CalibrationError(
            f"no calibration ships for explore.method={config.explore.method} with vlm.backend="
            f"{config.vlm.backend} (shipped: {shipped}). Make one with `homebot calibrate --suite SUITE "
            "--out FILE` and pass --set stop.calibration=FILE, or stop at the budget with --stop budget."
        )
    calibration = read_calibration(path)
    check_fits(calibration, path, config)
    return calibration, path


def check_fits(calibration: Calibration, path: Path, config: Config) -> None:
    """Refuse a calibration made with another policy or VLM, naming every difference, unless the
    config says to accept it."""
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
