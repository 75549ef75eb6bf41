"""Every module imports alone, in an interpreter where nothing of homebot was imported before it.

A circle of imports (module a needs b, which needs a back) hides while some other module happens to
import one side first: the tests pass, and a user's `import agent.planning.semantic` fails. Here a
parent process loads only the third-party libraries, then forks one child per module; each child
starts with no homebot module loaded and imports just its own. The pure libraries are checked the
same way for what they load with them: no py_trees, no Zenoh, no PyBullet, whatever they import
in turn.

The parent does not guess which third-party modules those are: a first child imports every homebot
module and names what else came with it, and the parent loads all of that (the frameworks aside,
when they are what is checked for) before the per-module children fork. Each child then spends
its time on homebot's own imports, not on scipy's or Rerun's.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from test_layers import PACKAGES, PURE, ROOT, _within

#: Third-party libraries the parent loads once, so each child imports only homebot's own code; the
#: rest of what homebot's modules bring with them is found by the first child (see the docstring).
THIRD_PARTY = ("numpy", "scipy", "torch", "open3d", "pinocchio", "ruckig", "matplotlib", "matplotlib.pyplot",
               "skimage", "networkx", "PIL", "py_trees", "zenoh", "pybullet")
#: What importing a pure library must not load.
FRAMEWORKS = ("py_trees", "zenoh", "pybullet")

_CHILDREN = r'''
import importlib, json, os, sys
modules, preload, banned = json.loads(sys.argv[1]), json.loads(sys.argv[2]), json.loads(sys.argv[3])
own = {module.split(".")[0] for module in modules}  # the packages checked: never preloaded

def in_child(work):
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        try:
            message = work()
        except BaseException as error:
            message = f"{type(error).__name__}: {error}"
        os.write(write, message.encode())
        os._exit(0)
    os.close(write)
    chunks = []
    while chunk := os.read(read, 65536):
        chunks.append(chunk)
    os.close(read)
    os.waitpid(pid, 0)
    return b"".join(chunks).decode()

def brought_along():
    before = set(sys.modules)
    for module in modules:
        try:
            importlib.import_module(module)
        except BaseException:
            pass  # reported by its own child below
    return json.dumps([name for name in sys.modules if name not in before and name.split(".")[0] not in own
                       and name.split(".")[0] not in banned])

for name in preload:
    importlib.import_module(name)
for name in json.loads(in_child(brought_along) or "[]"):
    try:
        importlib.import_module(name)
    except BaseException:
        pass  # a module that only loads as part of its package's own import

def import_alone(module):
    def work():
        importlib.import_module(module)
        loaded = sorted(name for name in banned if name in sys.modules)
        return f"loads {', '.join(loaded)}" if loaded else ""
    return work

found = {}
for module in modules:
    if message := in_child(import_alone(module)):
        found[module] = message
print(json.dumps(found))
'''


def _modules() -> list[str]:
    """Every module of the four packages, by dotted name (``__main__`` modules left out: they run)."""
    names = []
    for package in PACKAGES:
        for path in sorted((ROOT / package).rglob("*.py")):
            if path.name != "__main__.py":
                names.append(".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__"))
    return names


def _import_each(modules: list[str], preload: tuple[str, ...], banned: tuple[str, ...] = ()) -> dict[str, str]:
    """Module -> what went wrong importing it alone (an error, or banned modules it loaded)."""
    done = subprocess.run([sys.executable, "-c", _CHILDREN, json.dumps(modules), json.dumps(list(preload)),
                           json.dumps(list(banned))], capture_output=True, text=True, cwd=ROOT, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return json.loads(done.stdout.strip().splitlines()[-1])


def test_every_module_imports_alone() -> None:
    modules = _modules()
    assert len(modules) > 200
    assert _import_each(modules, THIRD_PARTY) == {}


def test_pure_libraries_load_no_framework_with_them() -> None:
    pure = [module for module in _modules() if _within(module, PURE)]
    assert len(pure) > 100
    allowed = tuple(name for name in THIRD_PARTY if name not in FRAMEWORKS)
    assert _import_each(pure, allowed, FRAMEWORKS) == {}


def test_the_check_catches_a_circle(tmp_path: Path) -> None:
    """Two modules that need each other at import time fail when the second is imported first."""
    package = tmp_path / "circle"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "a.py").write_text("from circle.b import B\nA = 1\n")
    (package / "b.py").write_text("from circle.a import A\nB = 2\n")
    script = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); exec(compile(open(sys.argv[4]).read(), 'x', 'exec'))"
    helper = tmp_path / "children.py"
    helper.write_text(_CHILDREN)
    done = subprocess.run([sys.executable, "-c", script, json.dumps(["circle.b"]), "[]", "[]", str(helper)],
                          capture_output=True, text=True, timeout=60)
    assert "ImportError" in json.loads(done.stdout.strip().splitlines()[-1])["circle.b"]
