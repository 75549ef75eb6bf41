"""Public functions say what they take and give: read from every module's source (ast), never by importing it.

A public function or method (its name and its class's name start with no ``_``) that takes a
parameter besides ``self``/``cls`` has a docstring with an ``Args:`` section; one annotated to return
something other than None has ``Returns:`` (``Yields:`` for a generator, or ``Returns:`` for
the context manager it makes). Left out: dunders, properties,
the py_trees callbacks whose meaning py_trees defines (`PY_TREES_CALLBACKS`), and methods that override
one of a base class in the four packages or implement one of a `Protocol` the module defines or imports
(the base or the protocol documents them). A context manager's ``Iterator[None]`` returns nothing.
"""

from __future__ import annotations

import ast
from collections.abc import Iterator
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
PACKAGES = ("agent", "behaviours", "skills", "worlds")
#: Behaviour callbacks py_trees documents; a leaf's one-line docstring says what it does there.
PY_TREES_CALLBACKS = frozenset({"setup", "initialise", "update", "terminate", "shutdown"})


def _modules() -> Iterator[Path]:
    for package in PACKAGES:
        yield from sorted((ROOT / package).rglob("*.py"))


def _is_property(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    for decorator in node.decorator_list:
        name = decorator.attr if isinstance(decorator, ast.Attribute) else getattr(decorator, "id", "")
        if name in ("property", "cached_property", "setter", "deleter"):
            return True
    return False


def _has_parameters(node: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> bool:
    args = node.args
    positional = [*args.posonlyargs, *args.args]
    if method and positional and positional[0].arg in ("self", "cls"):
        positional = positional[1:]
    return bool(positional or args.kwonlyargs or args.vararg or args.kwarg)


def _returns_something(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    returns = node.returns
    if returns is None:
        return False
    if isinstance(returns, ast.Subscript) and _base_name(returns) in ("Iterator", "Generator", "AsyncIterator"):
        returns = returns.slice.elts[0] if isinstance(returns.slice, ast.Tuple) else returns.slice
    return not (isinstance(returns, ast.Constant) and returns.value in (None, "None"))


def _is_generator(node: ast.FunctionDef | ast.AsyncFunctionDef) -> bool:
    def walk(body: ast.AST) -> Iterator[ast.AST]:
        for child in ast.iter_child_nodes(body):
            if not isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
                yield child
                yield from walk(child)
    return any(isinstance(child, (ast.Yield, ast.YieldFrom)) for child in walk(node))


def _base_name(base: ast.expr) -> str:
    if isinstance(base, ast.Subscript):
        base = base.value
    if isinstance(base, ast.Attribute):
        return base.attr
    return getattr(base, "id", "")


def _classes(trees: dict[Path, ast.Module]) -> dict[str, list[ast.ClassDef]]:
    """Class name -> the classes of that name in the four packages."""
    found: dict[str, list[ast.ClassDef]] = {}
    for tree in trees.values():
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                found.setdefault(node.name, []).append(node)
    return found


def _inherited(cls: ast.ClassDef, classes: dict[str, list[ast.ClassDef]], seen: set[str] | None = None) -> set[str]:
    """The method names ``cls`` inherits from its bases within the four packages."""
    seen = set() if seen is None else seen
    names: set[str] = set()
    for base in cls.bases:
        name = _base_name(base)
        if name in seen:
            continue
        seen.add(name)
        for parent in classes.get(name, []):
            names.update(n.name for n in parent.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef)))
            names |= _inherited(parent, classes, seen)
    return names


def _protocol_methods(tree: ast.Module, classes: dict[str, list[ast.ClassDef]]) -> set[str]:
    """The method names of the protocols ``tree`` defines or imports by name."""
    names = {node.name for node in tree.body if isinstance(node, ast.ClassDef)}
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            names.update(alias.name for alias in node.names)
    return {member.name for name in names for cls in classes.get(name, [])
            if any(_base_name(base) == "Protocol" for base in cls.bases)
            for member in cls.body if isinstance(member, (ast.FunctionDef, ast.AsyncFunctionDef))}


def _problems(node: ast.FunctionDef | ast.AsyncFunctionDef, where: str) -> list[str]:
    docstring = ast.get_docstring(node) or ""
    found = []
    if _has_parameters(node, method="." in where) and "Args:" not in docstring:
        found.append(f"{where}: no Args:" if docstring else f"{where}: no docstring")
    if _returns_something(node):
        sections = ("Yields:", "Returns:") if _is_generator(node) else ("Returns:",)
        if not any(section in docstring for section in sections):
            found.append(f"{where}: no {sections[0]}")
    return found


def _undocumented() -> list[str]:
    trees = {path: ast.parse(path.read_text(encoding="utf-8")) for path in _modules()}
    classes = _classes(trees)
    found: list[str] = []
    for path, tree in trees.items():
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        protocol = _protocol_methods(tree, classes)
        for node in tree.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and not node.name.startswith("_"):
                found += _problems(node, f"{module}:{node.name}")
            elif isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                is_protocol = any(_base_name(base) == "Protocol" for base in node.bases)
                inherited = _inherited(node, classes) | (set() if is_protocol else protocol)
                for member in node.body:
                    if (not isinstance(member, (ast.FunctionDef, ast.AsyncFunctionDef)) or member.name.startswith("_")
                            or member.name in PY_TREES_CALLBACKS or member.name in inherited or _is_property(member)):
                        continue
                    found += _problems(member, f"{module}:{node.name}.{member.name}")
    return found


def test_public_functions_document_args_and_returns() -> None:
    found = _undocumented()
    assert not found, f"{len(found)} public functions lack docstring sections:\n" + "\n".join(found)
