"""A skill from another package, installed with pip, runs without editing homebot: on its own with
`homebot skill run`, and inside the EQA tree, put there by settings alone, against a real world."""

from __future__ import annotations

import base64
import hashlib
import json
import os
import zipfile
import subprocess
import sys
from pathlib import Path

import pytest

from worlds.bus.session import free_tcp_endpoint

pytestmark = pytest.mark.slow

SKILL = '''
"""A skill of another package: note where the robot stands."""

import json

import py_trees

from agent.observation import Observation
from skills.ports import PortedSkill, input_port, output_port


class NotePose(PortedSkill):
    """Note where the robot stands, from the newest frame or by asking the world."""

    skill_name = "note_pose"
    ports = (
        input_port("path", str, "the file each pose is appended to"),
        input_port("observation", Observation, "the newest frame; without it the world is asked", default=None),
        output_port("notes", int, "how many poses were noted so far"),
    )

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.noted = 0

    def update(self):
        if self.input_problem():
            self.feedback_message = self.input_problem()
            return py_trees.common.Status.FAILURE
        frame = self.inputs["observation"]
        if frame is None:
            frame = Observation.from_message(self.link.call("observe", {}))
        with open(self.inputs["path"], "a") as out:
            out.write(json.dumps([round(float(v), 3) for v in frame.base_pose]) + "\\n")
        self.noted += 1
        self.set_output("notes", self.noted)
        self.feedback_message = f"noted pose {self.noted}"
        return py_trees.common.Status.SUCCESS
'''

def _wheel(folder: Path) -> Path:
    """The package `pose-notes` as a wheel: its module, its metadata and its one entry point.

    Written by hand (a wheel is a zip with a fixed layout), so installing it needs no build backend
    and no network."""
    info = "pose_notes-0.1.0.dist-info"
    files = {
        "pose_notes.py": SKILL,
        f"{info}/METADATA": "Metadata-Version: 2.1\nName: pose-notes\nVersion: 0.1.0\n",
        f"{info}/WHEEL": "Wheel-Version: 1.0\nGenerator: hand\nRoot-Is-Purelib: true\nTag: py3-none-any\n",
        f"{info}/entry_points.txt": "[homebot.skills]\nnote_pose = pose_notes:NotePose\n",
    }
    record = [f"{name},sha256={_digest(text)},{len(text.encode())}" for name, text in files.items()]
    files[f"{info}/RECORD"] = "\n".join([*record, f"{info}/RECORD,,"]) + "\n"
    path = folder / "pose_notes-0.1.0-py3-none-any.whl"
    with zipfile.ZipFile(path, "w") as wheel:
        for name, text in files.items():
            wheel.writestr(name, text)
    return path


def _digest(text: str) -> str:
    return base64.urlsafe_b64encode(hashlib.sha256(text.encode()).digest()).rstrip(b"=").decode()


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """The environment of a shell where the package `pose-notes` is pip-installed (into a target
    folder on PYTHONPATH, so the test leaves the virtual environment as it found it)."""
    root = tmp_path_factory.mktemp("pose-notes")
    target = root / "site"
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-index",
                           "--target", str(target), str(_wheel(root))], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (target / "pose_notes-0.1.0.dist-info" / "entry_points.txt").exists()
    return {**os.environ, "PYTHONPATH": str(target)}


def _homebot(env: dict[str, str], *args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "agent.app.cli", *args], capture_output=True, text=True, env=env,
                          cwd=cwd, timeout=300)


def test_the_installed_skill_is_listed_with_its_ports(installed: dict[str, str], tmp_path: Path) -> None:
    listed = _homebot(installed, "skills", "--json", cwd=tmp_path)
    rows = {row["name"]: row for row in json.loads(listed.stdout)}
    assert rows["note_pose"]["package"] == "pose-notes"
    assert "input path (str, required): the file each pose is appended to" in rows["note_pose"]["ports"]


def test_homebot_skill_run_runs_it_against_a_world(installed: dict[str, str], tmp_path: Path) -> None:
    notes = tmp_path / "poses.jsonl"
    done = _homebot(installed, "skill", "run", "note_pose", "--port", f"path={notes}", "--seed", "3", "--json",
                    cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    outcome = json.loads(done.stdout)
    assert outcome == {"status": "SUCCESS", "feedback": "noted pose 1", "outputs": {"notes": 1}}
    assert len(notes.read_text().splitlines()) == 1
    wrong = _homebot(installed, "skill", "run", "note_pose", "--port", "speed=2", cwd=tmp_path)
    assert wrong.returncode == 2 and "note_pose: no port called 'speed'" in wrong.stderr


def test_settings_put_it_into_the_eqa_tree_where_it_runs_every_step(installed: dict[str, str],
                                                                     tmp_path: Path) -> None:
    notes = tmp_path / "poses.jsonl"
    plug = [{"skill": "note_pose", "after": "IntegrateMap", "ports": {"path": str(notes),
                                                                       "observation": "{observation}"}}]
    done = _homebot(installed, "run", "--listen", free_tcp_endpoint(), "--seed", "3", "--stop", "budget", "--set", "episode.budget=3",
                    "--set", f"tree.skills={json.dumps(plug)}", "--out", str(tmp_path / "runs"), cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    poses = [json.loads(line) for line in notes.read_text().splitlines()]
    assert len(poses) == 3 and len({tuple(pose) for pose in poses}) > 1  # one per step, as the robot moved
    [result] = (tmp_path / "runs").glob("*/result.json")
    assert json.loads(result.read_text())["steps"] == 3
    snapshots = (result.parent / "snapshots.jsonl").read_text()
    assert '"NotePose"' in snapshots


def test_a_misplaced_skill_stops_the_run_before_the_world_starts(installed: dict[str, str], tmp_path: Path) -> None:
    plug = [{"skill": "note_pose", "after": "IntegrateMap", "ports": {"paht": "x"}}]
    done = _homebot(installed, "run", "--listen", free_tcp_endpoint(), "--set", f"tree.skills={json.dumps(plug)}", "--out", str(tmp_path), cwd=tmp_path)
    assert done.returncode != 0
    assert "tree.skills[0]: note_pose: no port called 'paht'" in done.stderr
    assert not list(tmp_path.glob("*/world.log"))
