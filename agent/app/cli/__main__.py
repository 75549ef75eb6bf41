"""`python -m agent.app.cli`: the `homebot` command without its console script."""

from agent.app.cli import entry_point

entry_point()
