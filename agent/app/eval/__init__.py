"""Evaluations over suites, and the frontier network's training data: many episodes or homes in parallel,
results appended as each finishes, figures at the end."""
