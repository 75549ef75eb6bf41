"""The skill registry: a package that declares a skill in its metadata shows up in `homebot skills`."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

import py_trees
from py_trees.common import Access, Status

from skills.base import ArmSkill
from skills.context import SkillContext
from skills.ports import PortError
from skills.registry import SkillError, SkillRegistry

#: Skills made but never ticked against a world need no link.
CONTEXT = SkillContext(link=None)  # type: ignore[arg-type]

DEMO = '''
import py_trees

from skills.ports import PortedSkill, input_port, output_port


class Wave(PortedSkill):
    """Waves the gripper: a skill from another package."""

    skill_name = "wave"
    ports = (input_port("times", int, "how often to wave", default=2),
             output_port("waved", int, "how often it waved"))

    def update(self):
        if self.input_problem():
            self.feedback_message = self.input_problem()
            return py_trees.common.Status.FAILURE
        self.set_output("waved", self.inputs["times"])
        return py_trees.common.Status.SUCCESS


class Plain(py_trees.behaviour.Behaviour):
    """A behaviour that declares no ports."""


NOT_A_BEHAVIOUR = 3
'''


def _distribution(root: Path, name: str, entries: str) -> None:
    info = root / f"{name}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[homebot.skills]\n{entries}")


def _demo_package(root: Path) -> Path:
    """An installed distribution with a good skill, a missing class, a non-behaviour and a
    behaviour without ports."""
    (root / "demo_skills.py").write_text(DEMO)
    _distribution(root, "demo_skills", "wave = demo_skills:Wave\nmissing = demo_skills:Missing\n"
                                       "odd = demo_skills:NOT_A_BEHAVIOUR\nplain = demo_skills:Plain\n")
    return root


def test_a_declared_skill_is_listed_loaded_and_made_with_its_ports_bound(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(_demo_package(tmp_path)))
    registry = SkillRegistry()
    entries = {entry.name: entry for entry in registry.entries()}
    assert entries["wave"].target == "demo_skills:Wave" and entries["wave"].distribution == "demo_skills"
    wave = registry.create("wave", CONTEXT, {"times": "3"})
    assert type(wave).__name__ == "Wave" and wave.name == "Wave"
    wave.tick_once()
    assert wave.status == Status.SUCCESS and wave.outputs == {"waved": 3}
    with pytest.raises(SkillError, match="'missing'.*cannot be loaded"):
        registry.load("missing")
    with pytest.raises(SkillError, match="'odd'.*is not a skill"):
        registry.load("odd")
    with pytest.raises(SkillError, match="'plain'.*is not a skill"):
        registry.load("plain")
    with pytest.raises(SkillError, match="no skill called 'fly' is installed"):
        registry.load("fly")
    assert registry.problem("wave") == "" and "cannot be loaded" in registry.problem("missing")


def test_a_name_two_packages_declare_is_refused_naming_both(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(_demo_package(tmp_path)))
    _distribution(tmp_path, "other_skills", "stow = demo_skills:Wave\n")
    registry = SkillRegistry()
    with pytest.raises(SkillError, match=r"'stow' is declared twice: .*skills\.stow:Stow \(from homebot\) and "
                                         r"demo_skills:Wave \(from other_skills\)"):
        registry.load("stow")


def test_ports_are_bound_by_name_and_type_and_refused_with_the_port_named(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(_demo_package(tmp_path)))
    registry = SkillRegistry()
    with pytest.raises(PortError, match="wave: no port called 'speed' \\(its ports: times, waved\\)"):
        registry.create("wave", CONTEXT, {"speed": 1})
    with pytest.raises(PortError, match="wave: port 'times' \\(int\\): invalid literal"):
        registry.create("wave", CONTEXT, {"times": "often"})
    with pytest.raises(PortError, match="wave: port 'times' takes a int, not float"):
        registry.create("wave", CONTEXT, {"times": 2.5})
    with pytest.raises(PortError, match="move_camera: port 'look_point' is required"):
        registry.create("move_camera", CONTEXT)


def test_ports_bound_to_blackboard_keys_are_read_and_written_there(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(_demo_package(tmp_path)))
    board = py_trees.blackboard.Client(name="test")
    board.register_key("wave_count", access=Access.WRITE)
    board.register_key("waved_count", access=Access.READ)
    wave = SkillRegistry().create("wave", CONTEXT, {"times": "{wave_count}", "waved": "{waved_count}"})
    assert wave.blackboard.read == {"/wave_count"} and wave.blackboard.write == {"/waved_count"}
    wave.tick_once()
    assert wave.status == Status.FAILURE and "the blackboard has no 'wave_count'" in wave.feedback_message
    board.set("wave_count", 5)
    wave.tick_once()
    assert wave.status == Status.SUCCESS and board.get("waved_count") == 5


def test_homebot_skills_lists_them_and_flags_broken_ones(tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": str(_demo_package(tmp_path))}
    done = subprocess.run([sys.executable, "-m", "agent.app.cli", "skills", "--json"], capture_output=True, text=True,
                          env=env, timeout=60)
    rows = {row["name"]: row for row in json.loads(done.stdout)}
    assert rows["wave"]["summary"].startswith("Waves the gripper")
    assert rows["missing"]["summary"].startswith("BROKEN")
    table = subprocess.run([sys.executable, "-m", "agent.app.cli", "skills"], capture_output=True, text=True,
                           env=env, timeout=60)
    assert table.returncode == 1, "a broken skill should make the listing fail"
    assert "wave" in table.stdout and "demo_skills:Wave (demo_skills)" in table.stdout


def test_bench_skills_reports_ik_and_trajectory_figures() -> None:
    done = subprocess.run([sys.executable, "-m", "agent.app.cli", "bench", "skills", "--n", "3", "--json"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["n"] == 3 and report["dof"] == 8 and report["ik_success_rate"] == 1.0
    assert report["ik_ms_median"] > 0 and report["trajectory_ms_median"] > 0


def test_homebot_ships_the_seven_primitives_under_their_acsg_names() -> None:
    from agent.acsg.primitives import PRIMITIVES

    registry = SkillRegistry()
    shipped = {entry.name: entry for entry in registry.entries() if entry.distribution == "homebot"}
    assert set(shipped) == set(PRIMITIVES) | {"stow"}
    for name in shipped:
        skill = registry.load(name)
        assert skill.skill_name == name and issubclass(skill, ArmSkill)
        assert [port.name for port in skill.ports][:3] == ["surface_z", "label", "result"]
