"""Imports point one way: read from every module's source (ast), never by importing it.

The world is the bottom layer: it imports nothing of the agent, its behaviours or its skills (the
wire both speak is `worlds.bus`). The pure libraries of the agent test with plain arrays, so they
import nothing of py_trees, Zenoh, PyBullet, the settings, the runtime, the CLI, the evaluation,
the behaviours or the skills. `STILL_UPWARD` names the modules that do so today and what they
import; the list may only shrink: a module that stops is refused until it is taken off, and a new
upward import fails at once.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("agent", "behaviours", "skills", "worlds")
PURE = ("agent.mapping", "agent.planning", "agent.eqa", "agent.acsg", "agent.lfe", "agent.perception", "agent.vlm")
KEPT_OUT_OF_PURE = ("py_trees", "zenoh", "pybullet", "agent.config", "agent.runtime", "agent.cli", "agent.eval",
                    "agent.bench", "behaviours", "skills", "worlds.bus", "worlds.sim", "worlds.server")
#: Upward imports of pure libraries left to undo: module -> the imports it still makes.
STILL_UPWARD = {
    # the robot the act branch drives: arm skills and the world link in one class, to be split
    "agent.acsg.robot": {"agent.runtime.world_link", "skills", "skills.idle_space", "skills.plan",
                         "skills.primitives", "skills.stand", "skills.stow", "worlds.bus.rpc"},
    # training-data generation runs homes in a process pool: orchestration, not a library
    "agent.lfe.data": {"agent.runtime.pool"},
}


def _imports() -> dict[str, set[str]]:
    """Every module of the four packages -> the absolute module names it imports."""
    found: dict[str, set[str]] = {}
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            module = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
            names: set[str] = set()
            for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
                if isinstance(node, ast.Import):
                    names.update(alias.name for alias in node.names)
                elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                    names.add(node.module)
            found[module] = names
    return found


def _within(name: str, prefixes: tuple[str, ...]) -> bool:
    return any(name == prefix or name.startswith(prefix + ".") for prefix in prefixes)


def test_the_world_imports_nothing_of_the_agent_its_behaviours_or_its_skills() -> None:
    upward = {module: sorted(name for name in names if _within(name, ("agent", "behaviours", "skills")))
              for module, names in _imports().items() if _within(module, ("worlds",))}
    assert {module: names for module, names in upward.items() if names} == {}


def test_pure_libraries_import_no_runtime_framework_or_composition_root() -> None:
    upward = {module: {name for name in names if _within(name, KEPT_OUT_OF_PURE)}
              for module, names in _imports().items() if _within(module, PURE)}
    upward = {module: names for module, names in upward.items() if names}
    assert upward == STILL_UPWARD


def test_the_check_sees_an_upward_import() -> None:
    """The reader finds what a module imports, absolute and from-imports alike."""
    imports = _imports()
    assert "worlds.bus.codec" in imports["worlds.server"]
    assert "skills.stow" in imports["agent.acsg.robot"]
    assert len(imports) > 150
