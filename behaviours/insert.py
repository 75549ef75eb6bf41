"""Putting a behaviour into a built tree, next to a node named as `homebot watch` shows it.

This is how a skill installed by another package joins the EQA tree by settings alone (the
composition root makes the skill through the registry and calls `insert_after`), without editing
the tree's code.
"""

from __future__ import annotations

import py_trees


def insert_after(root: py_trees.behaviour.Behaviour, anchor: str, new: py_trees.behaviour.Behaviour) -> None:
    """Put ``new`` into the composite that holds the node called ``anchor``, right after it.

    Args:
        root: the tree's root.
        anchor: the name of the node ``new`` follows.
        new: the behaviour to insert.

    Raises:
        ValueError: no node, or more than one, is called ``anchor``, or it is the root (which has
            no composite to join); the text lists the names there are.
    """
    found = [node for node in root.iterate() if node.name == anchor]
    if len(found) != 1:
        names = sorted({node.name for node in root.iterate()})
        problem = "no node" if not found else f"{len(found)} nodes"
        raise ValueError(f"{problem} called {anchor!r} in the tree (its nodes: {', '.join(names)})")
    parent = found[0].parent
    if not isinstance(parent, py_trees.composites.Composite):
        raise ValueError(f"{anchor!r} is not inside a composite: nothing can follow it")
    parent.insert_child(new, parent.children.index(found[0]) + 1)
