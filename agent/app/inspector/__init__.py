"""`homebot inspect`: a behaviour-tree inspector in the browser, live or for a recorded run.

`history` keeps the whole states of a run's tree; `sources` fills it from the bus or a run folder
and forwards control requests to the agent; `server` serves the page (static/) and its JSON and
Server-Sent-Events API on a local port.
"""
