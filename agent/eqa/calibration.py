"""The calibration file: the non-conformity scores of N calibration episodes and what made them.

Conformal prediction promises coverage only for test episodes drawn like the calibration ones, so
the file records the exploration policy and VLM the scores came from (`made_with`, filled in by
`agent.app.runtime.calibrations` from the settings), and a run with a different policy or VLM refuses
it (`differences`). A checksum over the content catches a file edited or cut short by hand. Plain
JSON and numbers: no settings, no runtime.
"""

from __future__ import annotations

import hashlib
import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from agent.eqa.answers import steps_from_records
from agent.eqa.conformal import conformal_quantile, nonconformity

CALIBRATION_FORMAT = "homebot-calibration"
CALIBRATION_VERSION = 1


class CalibrationError(ValueError):
    """A calibration file that cannot be used; the text names the file and the problem."""


def suite_identity(path: Path, entries: int) -> dict[str, Any]:
    """Which question suite a calibration was made on: its file name, digest and number of entries.

    Args:
        path: the suite file.
        entries: how many of its questions were used.

    Returns:
        The identity, as kept in the calibration file.
    """
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
        """q̂(ε) over this file's scores (+∞ when N is too small for 1 − ε).

        Args:
            epsilon: ε, the error rate promised (0 < ε < 1).

        Returns:
            q̂(ε).
        """
        return conformal_quantile(self.kappas, epsilon)

    def to_json(self) -> dict[str, Any]:
        """The calibration file's JSON form, stamped with its format, version and creation time.

        Returns:
            The JSON object.
        """
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


def read_calibration(path: Path) -> Calibration:
    """Load and check a calibration file; every problem is named with the file.

    Args:
        path: the calibration file.

    Returns:
        The calibration.

    Raises:
        CalibrationError: the file is missing, unreadable, or not a calibration of this version.
    """
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


def differences(made: Any, now: Any, prefix: str = "") -> list[str]:
    """The dotted settings where ``now`` differs from ``made`` (both a calibration's `made_with`),
    each as a line saying both values.

    Args:
        made: the settings the calibration was made with (or a part of them).
        now: the settings now (the same part).
        prefix: the dotted path down to this part.

    Returns:
        The lines, sorted by setting.
    """
    if isinstance(made, dict) and isinstance(now, dict):
        found = []
        for key in sorted(set(made) | set(now)):
            found += differences(made.get(key), now.get(key), f"{prefix}{key}.")
        return found
    if made != now:
        return [f"{prefix.rstrip('.')}: calibrated with {made!r}, this run uses {now!r}"]
    return []
