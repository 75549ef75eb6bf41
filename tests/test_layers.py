"""Imports point one way: read from every module's source (ast), never by importing it.

The layers, bottom to top (docs/architecture.md draws them):

1. `worlds` — the simulated home, and `worlds.bus`, the wire both sides stand on. It imports
   nothing of the agent, its behaviours or its skills.
2. the pure libraries — `agent.{mapping, perception, planning, eqa, vlm, acsg, lfe}`, the small
   shared modules beside them, and the arm's `skills.arm`. They test with plain arrays, so they
   import no behaviour-tree, middleware or simulator framework, and nothing above them.
3. `skills` — arm skills as behaviours, their registry and the scene-graph executor; then
   `behaviours` — the EQA leaves and trees, which may use skills.
4. `agent.app` — the composition root: command line, settings, runtime, evaluation, benchmarks.
   It knows everything; nothing imports it.

`STILL_UPWARD` names imports that break these rules today; the list may only shrink.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("agent", "behaviours", "skills", "worlds")
APP = ("agent.app",)
PURE = ("agent.mapping", "agent.planning", "agent.eqa", "agent.acsg", "agent.lfe", "agent.perception", "agent.vlm",
        "agent.observation", "agent.timing", "agent.pose", "skills.arm")
#: What a pure library never imports: frameworks and every layer above it.
KEPT_OUT_OF_PURE = ("py_trees", "zenoh", "pybullet", "agent.app", "behaviours", "skills")
#: All a pure library takes from the world: plain data and functions, no simulator, no live wire.
WORLD_DATA = (
    "worlds.bus.codec",  # the wire format of a frame (`agent.observation` decodes it)
    "worlds.bus.questions",  # the question format: four choices, answered by letter
    "worlds.vocabulary",  # the label vocabulary frames carry (the simulated VLM knows it)
    "worlds.questions",  # the question templates (the simulated VLM parses them)
    "worlds.home", "worlds.freespace", "worlds.robot",  # homes the LFE coverage simulator explores and learns from
)
#: Upward imports left to undo: module -> the imports it still makes.
STILL_UPWARD: dict[str, set[str]] = {}


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


def _upward(importers: tuple[str, ...], forbidden: tuple[str, ...], allowed: tuple[str, ...] = ()
            ) -> dict[str, set[str]]:
    """Modules within ``importers`` -> what they import of ``forbidden`` (less ``allowed``)."""
    found = {module: {name for name in names if _within(name, forbidden) and not _within(name, allowed)}
             for module, names in _imports().items() if _within(module, importers)}
    return {module: names for module, names in found.items() if names}


def test_the_world_imports_nothing_of_the_agent_its_behaviours_or_its_skills() -> None:
    assert _upward(("worlds",), ("agent", "behaviours", "skills")) == {}


def test_pure_libraries_import_no_framework_and_nothing_above_them() -> None:
    assert _upward(PURE, KEPT_OUT_OF_PURE, allowed=("skills.arm",)) == STILL_UPWARD


def test_pure_libraries_take_only_plain_data_from_the_world() -> None:
    assert _upward(PURE, ("worlds",), allowed=WORLD_DATA) == {}


def test_skills_and_behaviours_reach_the_world_only_over_the_wire() -> None:
    """No leaf or skill touches the simulator: what it knows of the world comes over `worlds.bus`."""
    assert _upward(("skills", "behaviours"), ("worlds",), allowed=("worlds.bus",) + WORLD_DATA) == {}


def test_skills_never_import_the_behaviours_above_them() -> None:
    assert _upward(("skills",), ("behaviours",)) == {}


def test_nothing_imports_the_composition_root() -> None:
    assert _upward(("worlds", "behaviours", "skills") + PURE, APP) == STILL_UPWARD


def test_every_agent_module_is_in_a_layer() -> None:
    """A new top-level module of `agent` has to be placed: pure, or the composition root."""
    loose = [module for module in _imports() if _within(module, ("agent",)) and module != "agent"
             and not _within(module, PURE + APP)]
    assert loose == []


def test_the_check_sees_an_upward_import() -> None:
    """The reader finds what a module imports, absolute and from-imports alike."""
    imports = _imports()
    assert "worlds.bus.codec" in imports["worlds.server"]
    assert "skills.arm.planner" in imports["skills.robot_body"]
    assert len(imports) > 150
