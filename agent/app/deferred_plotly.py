"""Open3D without its Plotly drawing helpers until one is called: they load Dash and Plotly, which
cost every start of the agent a third of a second and nothing here draws with them.

``import open3d`` imports ``open3d.visualization``, which imports ``draw_plotly`` whatever the
program needs. `defer`, called before open3d is first imported, puts a stand-in under that module's
name whose functions import the real module on their first call and hand over to it; Open3D's own
names (``open3d.visualization.draw_plotly`` and the others) are pointed at the real functions then.
Once open3d has been imported, `defer` changes nothing.
"""

from __future__ import annotations

import importlib
import sys
import types
from collections.abc import Callable
from typing import Any

MODULE = "open3d.visualization.draw_plotly"
#: What ``open3d.visualization`` takes from the module.
NAMES = ("get_plotly_fig", "draw_plotly", "draw_plotly_server")


def defer() -> None:
    """Put the stand-in in place, unless open3d (or the real module) is imported already."""
    if "open3d" in sys.modules or MODULE in sys.modules:
        return
    stand_in = types.ModuleType(MODULE, "Stand-in for Open3D's Plotly helpers (agent.app.deferred_plotly).")
    for name in NAMES:
        setattr(stand_in, name, _on_first_call(stand_in, name))
    sys.modules[MODULE] = stand_in


def _on_first_call(stand_in: types.ModuleType, name: str) -> Callable[..., Any]:
    """``name`` of the real module, imported (in place of ``stand_in``) when first called."""
    def call(*args: Any, **kwargs: Any) -> Any:
        if sys.modules.get(MODULE) is stand_in:
            del sys.modules[MODULE]
        real = importlib.import_module(MODULE)
        package = sys.modules[MODULE.rpartition(".")[0]]
        for each in NAMES:  # as `from .draw_plotly import ...` left them, not the module
            setattr(package, each, getattr(real, each))
        return getattr(real, name)(*args, **kwargs)
    return call
