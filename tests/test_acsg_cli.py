"""`homebot acsg` through the main command line."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from worlds.tabletop import write_tabletop_suites


def test_plan_and_show_from_a_tabletop_suite(tmp_path: Path) -> None:
    suite = next(p for p in write_tabletop_suites(tmp_path) if p.name == "occlusion.jsonl")
    plan = subprocess.run([sys.executable, "-m", "agent.app.cli", "acsg", "plan", str(suite), "soap", "--seed", "0"],
                          capture_output=True, text=True, timeout=60)
    assert plan.returncode == 0, plan.stderr
    assert plan.stdout.splitlines() == ["1. pick away shampoo (o4)", "2. open door (o6)", "3. pick soap (o3)"]
    picture = tmp_path / "graph.png"
    show = subprocess.run([sys.executable, "-m", "agent.app.cli", "acsg", "show", str(suite), "--seed", "0",
                           "--out", str(picture)], capture_output=True, text=True, timeout=60)
    assert show.returncode == 0 and picture.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    unknown = subprocess.run([sys.executable, "-m", "agent.app.cli", "acsg", "plan", str(suite), "apple", "--seed", "0"],
                             capture_output=True, text=True, timeout=60)
    assert unknown.returncode == 1 and "labels are:" in unknown.stderr
