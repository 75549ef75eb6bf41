"""The composition root: the command line, settings, the episode runtime, evaluations and benchmarks.

It knows every layer below it; nothing imports it.
"""
