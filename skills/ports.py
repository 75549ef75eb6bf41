"""Ports: what a skill takes and gives, declared on its class, as BehaviorTree.CPP declares a node's.

A skill lists its ports in the class attribute ``ports``::

    class Wave(PortedSkill):
        ports = (input_port("times", int, "how often to wave", default=2),
                 output_port("waved", int, "how often it did"))

Whoever makes the skill binds each port, by name, to a value (``{"times": 3}``, or the text ``"3"``
from a command line or a settings file, parsed by the port's type) or to a blackboard key, written
in braces as BehaviorTree.CPP writes it (``{"times": "{wave_count}"}``). A port left unbound takes its
default; a required one (no default) must be bound. An input bound to a key is read when the skill
starts (`PortedSkill.initialise`), an output bound to a key is written there; every output is also
kept on the skill (`PortedSkill.outputs`), so a caller that runs the skill itself needs no blackboard.
The skill registers each key it is bound to with the access it uses, READ or WRITE.

Binding errors (an unknown port, a value of the wrong type, a required port left unbound) are
`PortError`s naming the skill and the port, raised when the skill is made, before anything moves.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, ClassVar, Mapping

import numpy as np
import py_trees
from py_trees.common import Access

from skills.context import SkillContext
from worlds.bus.link import WorldLink


class _Required:
    def __repr__(self) -> str:
        return "REQUIRED"


#: The default of a port that must be bound.
REQUIRED: Any = _Required()
_KEY = re.compile(r"^\{([A-Za-z_/][\w/.]*)\}$")


class PortError(ValueError):
    """A port bound wrongly; the text names the skill, the port and the problem."""


@dataclass(frozen=True)
class Port:
    """One input or output of a skill: its ``name``, the ``type`` its values have, what it means
    (``doc``), and for an input its ``default`` (`REQUIRED`: none; None: the skill decides)."""

    name: str
    direction: str  # "input" or "output"
    type: type
    doc: str
    default: Any = REQUIRED

    @property
    def required(self) -> bool:
        return self.direction == "input" and self.default is REQUIRED

    def check(self, value: Any, skill: str) -> Any:
        """``value`` as this port's type, text parsed; `PortError` when it is not one.

        Args:
            value: a value of the port's type, or text to parse into one (``"0.2,0.1,0.8"`` for
                an array, ``"true"`` for a bool).
            skill: the skill's name, for the message.

        Returns:
            The value, converted (an int for a float port becomes a float; a list an array).
        """
        if value is None and self.default is None:
            return None
        try:
            if isinstance(value, str) and self.type is not str:
                return _parse(value, self.type)
            if self.type is float and isinstance(value, (int, float)) and not isinstance(value, bool):
                return float(value)
            if self.type is np.ndarray and isinstance(value, (list, tuple, np.ndarray)):
                return np.asarray(value, dtype=float)
        except ValueError as error:
            raise PortError(f"{skill}: port {self.name!r} ({self.type.__name__}): {error}") from None
        if not isinstance(value, self.type) or (self.type is int and isinstance(value, bool)):
            raise PortError(f"{skill}: port {self.name!r} takes a {self.type.__name__}, "
                            f"not {type(value).__name__} {value!r:.60}")
        return value

    def describe(self) -> str:
        """One line for listings: ``name (type, default): doc``.

        Returns:
            The line.
        """
        default = "" if self.direction == "output" else (
            ", required" if self.required else f", default {self.default!r}")
        return f"{self.direction} {self.name} ({self.type.__name__}{default}): {self.doc}"


def input_port(name: str, type_: type, doc: str, default: Any = REQUIRED) -> Port:
    """An input port (see `Port`); ``default=REQUIRED`` makes it one that must be bound.

    Args:
        name: the port's name, as bound and as read.
        type_: the type its value must have.
        doc: what the value is, for listings.
        default: the value when unbound, or `REQUIRED`.

    Returns:
        The port.
    """
    return Port(name, "input", type_, doc, default)


def output_port(name: str, type_: type, doc: str) -> Port:
    """An output port (see `Port`).

    Args:
        name: the port's name.
        type_: the type of what the skill gives there.
        doc: what the value is, for listings.

    Returns:
        The port.
    """
    return Port(name, "output", type_, doc)


def _parse(text: str, type_: type) -> Any:
    """A value of ``type_`` from command-line text."""
    if type_ is bool:
        if text.lower() in ("1", "true", "yes", "on"):
            return True
        if text.lower() in ("0", "false", "no", "off"):
            return False
        raise ValueError(f"{text!r} is not true or false")
    if type_ in (int, float):
        return type_(text)
    if type_ is np.ndarray:
        return np.array([float(part) for part in text.split(",")], dtype=float)
    raise ValueError(f"cannot be given as text ({text!r}); bind it to a blackboard key instead, e.g. {{key}}")


def blackboard_key(binding: Any) -> str | None:
    """The key of a binding written ``"{key}"``; None for a value.

    Args:
        binding: a port's binding: a value, or ``"{key}"``.

    Returns:
        The blackboard key, or None when the binding is a value.
    """
    match = _KEY.match(binding) if isinstance(binding, str) else None
    return match.group(1) if match else None


class PortedSkill(py_trees.behaviour.Behaviour):
    """Base of every skill: a behaviour made from a `SkillContext` whose inputs and outputs are
    its declared `ports`, bound when it is made.

    Subclasses set ``skill_name`` (the name it is registered under) and ``ports``, and implement
    ``update`` as any py_trees behaviour does: fail with `input_problem` when it says one, read the
    inputs from `inputs` (filled as the skill starts), give results with `set_output`.
    """

    skill_name: ClassVar[str] = ""
    ports: ClassVar[tuple[Port, ...]] = ()

    def __init__(self, context: SkillContext, name: str | None = None, bindings: Mapping[str, Any] | None = None
                 ) -> None:
        """Make the skill and bind its ports.

        Args:
            context: the world link and what skills run in it share.
            name: the node's name in a tree (default: the class name).
            bindings: port name -> value, text, or ``"{key}"`` of the blackboard.

        Raises:
            PortError: a port that does not exist, a value of the wrong type, a required port unbound.
        """
        super().__init__(name or type(self).__name__)
        self.context = context
        bindings = dict(bindings or {})
        declared = {port.name: port for port in self.ports}
        label = self.skill_name or type(self).__name__
        unknown = sorted(set(bindings) - set(declared))
        if unknown:
            raise PortError(f"{label}: no port called {', '.join(map(repr, unknown))} "
                            f"(its ports: {', '.join(declared) or 'none'})")
        self._values: dict[str, Any] = {}
        self._keys: dict[str, str] = {}
        self.blackboard = self.attach_blackboard_client(name=self.name)
        for port in self.ports:
            binding = bindings.get(port.name, port.default)
            key = blackboard_key(binding)
            if key is not None:
                self._keys[port.name] = key
                self.blackboard.register_key(key, access=Access.READ if port.direction == "input" else Access.WRITE)
            elif port.direction == "input":
                if binding is REQUIRED:
                    raise PortError(f"{label}: port {port.name!r} is required: {port.doc}")
                self._values[port.name] = port.check(binding, label)
        self.inputs: Mapping[str, Any] = MappingProxyType({})
        self.outputs: dict[str, Any] = {}
        self._input_problem = ""

    @property
    def link(self) -> WorldLink:
        """The world the skill acts in (its context's link)."""
        return self.context.link

    def initialise(self) -> None:
        """Read the inputs (the blackboard's for those bound to a key) and forget the last outputs."""
        self.outputs = {}
        self.inputs, self._input_problem = self._read_inputs()

    def _read_inputs(self) -> tuple[Mapping[str, Any], str]:
        values, label = dict(self._values), self.skill_name or type(self).__name__
        for port in self.ports:
            key = self._keys.get(port.name)
            if port.direction != "input" or key is None:
                continue
            if not self.blackboard.exists(key):
                return MappingProxyType(values), f"{label}: port {port.name!r}: the blackboard has no {key!r}"
            try:
                values[port.name] = port.check(self.blackboard.get(key), label)
            except PortError as error:
                return MappingProxyType(values), f"{error} (read from {key!r})"
        return MappingProxyType(values), ""

    def bound_keys(self) -> frozenset[str]:
        """The blackboard keys the ports are bound to, which a board's contract check allows.

        Returns:
            The keys, without their leading "/".
        """
        return frozenset(self._keys.values())

    def input_problem(self) -> str:
        """Why the inputs could not be read as the skill started ("" when they were).

        Returns:
            The problem, or "".
        """
        return self._input_problem

    def set_output(self, name: str, value: Any) -> None:
        """Give the output ``name``: kept in `outputs`, and written to its key when bound to one.

        Args:
            name: the output port's name.
            value: what the skill gives there.
        """
        self.outputs[name] = value
        if name in self._keys:
            self.blackboard.set(self._keys[name], value)
