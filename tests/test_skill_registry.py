"""The skill registry: a package that declares a skill in its metadata shows up in `homebot skills`."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from skills.registry import SkillError, installed_skills, load_skill

DEMO = '''
import py_trees


class Wave(py_trees.behaviour.Behaviour):
    """Waves the gripper: a skill from another package."""

    def update(self):
        return py_trees.common.Status.SUCCESS


NOT_A_BEHAVIOUR = 3
'''


def _demo_package(root: Path) -> Path:
    """An installed distribution with three skills: a good one, a missing class, a non-behaviour."""
    (root / "demo_skills.py").write_text(DEMO)
    info = root / "demo_skills-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: demo-skills\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(
        "[homebot.skills]\nwave = demo_skills:Wave\nmissing = demo_skills:Missing\nodd = demo_skills:NOT_A_BEHAVIOUR\n"
    )
    return root


def test_a_declared_skill_is_listed_and_loads(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.syspath_prepend(str(_demo_package(tmp_path)))
    entries = {entry.name: entry for entry in installed_skills()}
    assert entries["wave"].target == "demo_skills:Wave" and entries["wave"].distribution == "demo-skills"
    wave = load_skill("wave")
    assert wave.__name__ == "Wave" and entries["wave"].summary() == "Waves the gripper: a skill from another package."
    with pytest.raises(SkillError, match="'missing'.*cannot be loaded"):
        load_skill("missing")
    with pytest.raises(SkillError, match="not a py_trees behaviour class"):
        load_skill("odd")
    with pytest.raises(SkillError, match="no skill called 'fly' is installed"):
        load_skill("fly")


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
    assert "wave" in table.stdout and "demo_skills:Wave (demo-skills)" in table.stdout


def test_bench_skills_reports_ik_and_trajectory_figures() -> None:
    done = subprocess.run([sys.executable, "-m", "agent.app.cli", "bench", "skills", "--n", "3", "--json"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    assert report["n"] == 3 and report["dof"] == 8 and report["ik_success_rate"] == 1.0
    assert report["ik_ms_median"] > 0 and report["trajectory_ms_median"] > 0


def test_homebot_ships_the_seven_primitives_under_their_acsg_names() -> None:
    from agent.acsg.primitives import PRIMITIVES
    from skills.primitives import PRIMITIVES as SHIPPED

    entries = {entry.name: entry for entry in installed_skills() if entry.distribution == "homebot"}
    assert set(entries) == set(SHIPPED) | {"stow"} and set(SHIPPED) <= set(PRIMITIVES)
    for name, skill in SHIPPED.items():
        assert load_skill(name) is skill and skill.skill_name == name
