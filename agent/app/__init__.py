"""The composition root: the command line, settings, the episode runtime, evaluations and benchmarks.

It knows every layer below it; nothing imports it.
"""

from agent.app.deferred_plotly import defer

defer()  # before anything here imports open3d (the map, through the settings)
