"""Evaluations over suites: many episodes in parallel, results appended, figures at the end."""
