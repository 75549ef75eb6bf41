"""`python -m agent.app.cli`: the `homebot` command without its console script."""

import sys

from agent.app.cli import main

sys.exit(main())
